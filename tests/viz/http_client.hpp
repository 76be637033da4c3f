#pragma once
// Just enough of an HTTP and WebSocket client for the server's tests, on raw sockets: the tests
// must be able to send what no library would (garbage, a request line without a version, an
// oversized header) and to stop reading whenever they like. And a child process with its stdout
// on a pipe, to run stride-viz as a user does.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace stride::viz::test {

using Clock = std::chrono::steady_clock;

// A loopback TCP connection; rcvbuf > 0 sets SO_RCVBUF before connecting (a small window makes a
// client that does not read back up the server quickly). -1 on failure.
inline int connectTo(int port, int rcvbuf = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  if (rcvbuf > 0) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_port = htons(static_cast<std::uint16_t>(port));
  at.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&at), sizeof at) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

inline bool sendAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// Up to `n` bytes within the timeout; "" on timeout, EOF or error.
inline std::string recvSome(int fd, std::size_t n, double timeout_s) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, static_cast<int>(timeout_s * 1000)) <= 0) return "";
  std::string buf(n, '\0');
  const ssize_t got = ::recv(fd, buf.data(), n, 0);
  if (got <= 0) return "";
  buf.resize(static_cast<std::size_t>(got));
  return buf;
}

// Exactly n bytes, or false.
inline bool recvExactly(int fd, std::size_t n, std::string& out, double timeout_s) {
  out.clear();
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (out.size() < n) {
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    if (left <= 0) return false;
    const std::string part = recvSome(fd, n - out.size(), left);
    if (part.empty()) return false;
    out += part;
  }
  return true;
}

// Everything until the peer closes (or the timeout).
inline std::string recvAll(int fd, double timeout_s) {
  std::string out;
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    if (left <= 0) return out;
    const std::string part = recvSome(fd, 65536, left);
    if (part.empty()) return out;
    out += part;
  }
}

struct Reply {
  int status = 0;  // 0: the connection closed without an answer
  std::string head, body;
};

inline Reply parseReply(const std::string& raw) {
  Reply r;
  const auto end = raw.find("\r\n\r\n");
  if (raw.rfind("HTTP/1.1 ", 0) != 0 || end == std::string::npos) return r;
  r.status = std::stoi(raw.substr(9, 3));
  r.head = raw.substr(0, end);
  r.body = raw.substr(end + 4);
  return r;
}

// Sends raw bytes on a new connection and reads until the server closes it.
inline Reply roundTrip(int port, const std::string& bytes, double timeout_s = 10) {
  const int fd = connectTo(port);
  if (fd < 0) return {};
  sendAll(fd, bytes);  // the server may close before taking it all
  const std::string raw = recvAll(fd, timeout_s);
  ::close(fd);
  return parseReply(raw);
}

inline Reply get(int port, const std::string& target) {
  return roundTrip(port,
                   "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
}

// A WebSocket opened on /ws: the 101 answer is read byte by byte so that no frame is consumed.
// -1 when the server did not switch protocols.
inline int openWebSocket(int port, int rcvbuf = 0) {
  const int fd = connectTo(port, rcvbuf);
  if (fd < 0) return -1;
  sendAll(fd,
          "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
          "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
  std::string head, byte;
  while (head.size() < 4096 && head.find("\r\n\r\n") == std::string::npos) {
    if (!recvExactly(fd, 1, byte, 10)) break;
    head += byte;
  }
  if (head.rfind("HTTP/1.1 101", 0) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// The next text message from the server (unmasked frames, fragments joined, control frames
// skipped); "" on timeout.
inline std::string readWebSocketText(int fd, double timeout_s = 10) {
  std::string h, ext, payload, message;
  bool text = false;
  for (;;) {
    if (!recvExactly(fd, 2, h, timeout_s)) return "";
    const bool fin = (h[0] & 0x80) != 0;
    const int opcode = h[0] & 0x0f;
    std::uint64_t len = static_cast<unsigned char>(h[1]) & 0x7f;
    if (len == 126 || len == 127) {
      if (!recvExactly(fd, len == 126 ? 2 : 8, ext, timeout_s)) return "";
      len = 0;
      for (const char c : ext) len = (len << 8) | static_cast<unsigned char>(c);
    }
    if (!recvExactly(fd, static_cast<std::size_t>(len), payload, timeout_s)) return "";
    if (opcode == 1) {
      text = true;
      message = payload;
    } else if (opcode == 0 && text) {
      message += payload;
    } else {
      continue;  // ping, pong, close, binary
    }
    if (fin) return message;
  }
}

// VmRSS [kB] of a process ("self" or a pid), -1 if unknown.
inline long vmRssKb(const std::string& pid = "self") {
  std::ifstream status("/proc/" + pid + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// A program run with its stdout on a pipe (stderr inherited); killed at destruction.
class Child {
 public:
  explicit Child(const std::vector<std::string>& args) {
    int out[2];
    if (::pipe(out) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(out[1], 1);
      ::close(out[0]);
      ::close(out[1]);
      std::vector<char*> argv;
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(out[1]);
    out_ = out[0];
  }
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_ >= 0) ::close(out_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  int pid() const { return pid_; }
  // One line of its stdout (without the newline); "" on timeout or EOF.
  std::string readLine(double timeout_s) {
    std::string line, c;
    while (recvOne(c, timeout_s)) {
      if (c == "\n") return line;
      line += c;
    }
    return line;
  }
  // Sends the signal, waits for the exit; returns the exit status (-1: killed by a signal).
  int stop(int signal = SIGTERM) {
    ::kill(pid_, signal);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  // What it wrote after the lines read so far (call after stop()).
  std::string rest() {
    std::string all, c;
    while (recvOne(c, 1.0)) all += c;
    return all;
  }

 private:
  bool recvOne(std::string& c, double timeout_s) {
    pollfd p{out_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout_s * 1000)) <= 0) return false;
    char ch;
    if (::read(out_, &ch, 1) != 1) return false;
    c.assign(1, ch);
    return true;
  }
  int pid_ = -1, out_ = -1;
};

}  // namespace stride::viz::test
