#include "tools/teleop/raw_terminal.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace stride::teleop {

RawTerminal::RawTerminal(int fd) : fd_(fd) {
  if (tcgetattr(fd_, &saved_) != 0)
    throw std::runtime_error(std::string("not a terminal: ") + std::strerror(errno));
  termios raw = saved_;
  // No line buffering, echo, signals from keys (ISIG: Ctrl-C becomes a byte), Ctrl-V, flow
  // control (Ctrl-S/Q) or CR -> NL translation; read() returns what is there (poll() waits).
  raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO | ISIG | IEXTEN);
  raw.c_iflag &= ~static_cast<tcflag_t>(IXON | ICRNL | INLCR | ISTRIP);
  raw.c_cc[VMIN] = 0;
  raw.c_cc[VTIME] = 0;
  if (tcsetattr(fd_, TCSAFLUSH, &raw) != 0)
    throw std::runtime_error(std::string("cannot set raw mode: ") + std::strerror(errno));
  active_ = true;
}

RawTerminal::~RawTerminal() {
  restore();
}

void RawTerminal::restore() {
  if (!active_) return;
  tcsetattr(fd_, TCSAFLUSH, &saved_);
  active_ = false;
}

}  // namespace stride::teleop
