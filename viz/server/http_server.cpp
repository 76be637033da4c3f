#include "viz/server/http_server.hpp"

#include <algorithm>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace stride::viz {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
namespace fs = std::filesystem;

namespace {

// A request's header beyond this is refused (400): the page's requests are a few hundred bytes.
constexpr std::uint32_t kHeaderLimit = 8192;
// A connection that sends no complete request for this long is closed (also an idle keep-alive).
constexpr auto kReadTimeout = std::chrono::seconds(30);
// An answer the client does not take within this long is abandoned (the largest, /api/log, is a
// few MB).
constexpr auto kWriteTimeout = std::chrono::seconds(120);
// The page sends nothing on /ws; a larger message closes the connection.
constexpr std::size_t kWsMessageMax = 4096;

const char* mimeType(std::string_view path) {
  const auto dot = path.rfind('.');
  const std::string_view ext = dot == std::string_view::npos ? "" : path.substr(dot + 1);
  if (ext == "html") return "text/html; charset=utf-8";
  if (ext == "js" || ext == "mjs") return "text/javascript; charset=utf-8";
  if (ext == "css") return "text/css; charset=utf-8";
  if (ext == "json" || ext == "map") return "application/json";
  if (ext == "svg") return "image/svg+xml";
  if (ext == "png") return "image/png";
  if (ext == "jpg" || ext == "jpeg") return "image/jpeg";
  if (ext == "ico") return "image/x-icon";
  if (ext == "woff2") return "font/woff2";
  if (ext == "urdf" || ext == "xml" || ext == "dae") return "application/xml";
  if (ext == "stl" || ext == "STL") return "model/stl";
  if (ext == "obj" || ext == "txt") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

// A path segment a request may name: plain characters, not hidden, never "." or "..".
bool safeSegment(std::string_view s) {
  if (s.empty() || s.front() == '.') return false;
  for (const char c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
          c == '-' || c == '.'))
      return false;
  return true;
}

// "/assets/a/b.js" -> "assets/a/b.js" when every segment is safe, else nullopt.
std::optional<std::string> safeRelativePath(std::string_view path) {
  std::string out;
  while (!path.empty()) {
    if (path.front() != '/') return std::nullopt;
    path.remove_prefix(1);
    const std::string_view segment = path.substr(0, path.find('/'));
    if (!safeSegment(segment)) return std::nullopt;
    if (!out.empty()) out += '/';
    out += segment;
    path.remove_prefix(segment.size());
  }
  return out.empty() ? std::nullopt : std::optional<std::string>(out);
}

bool isHttpError(const beast::error_code& ec) {
  return ec.category() == http::make_error_code(http::error::bad_target).category();
}

}  // namespace

FrameText frameText(const Json& frame) {
  return std::make_shared<const std::string>(
      frame.dump(-1, ' ', false, Json::error_handler_t::replace));
}

class WsSession;

class HttpServer::Impl {
 public:
  Impl(ServerOptions o, Json i) : options(std::move(o)), info(std::move(i)) {}
  ~Impl();

  void listen();
  void accept();
  void doStop();
  void armInfoTimer();

  bool clientsFull() const {
    std::lock_guard<std::mutex> lock(mutex);
    return static_cast<int>(clients.size()) >= options.max_clients;
  }
  void addClient(const std::shared_ptr<WsSession>& session);
  void removeClient(const WsSession* session);
  FrameText infoFrame(const WsSession& session) const;
  Json apiInfo() const;
  ServerCounters counters() const;

  // Destroyed last, after the loop: the sessions the loop still holds count on them.
  std::atomic<std::uint64_t> clients_served{0}, frames_sent{0}, requests{0}, bad_requests{0};
  std::atomic<int> connections{0};
  // Then the loop, destroyed after every I/O object below (members go in reverse order).
  asio::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  asio::signal_set signals{ioc};
  asio::steady_timer info_timer{ioc}, stop_timer{ioc};
  ServerOptions options;
  Json info;
  tcp::endpoint endpoint;

  mutable std::mutex mutex;  // guards what follows, shared with the source's thread
  std::shared_ptr<const RobotFiles> files;
  FrameText model, terrain;
  std::shared_ptr<const std::string> log_document;
  Json source = Json::object();
  std::vector<std::shared_ptr<WsSession>> clients;
  std::uint64_t dropped_by_gone = 0, dropped_bytes_by_gone = 0;  // by clients that left
};

// One WebSocket client: its queue is filled by broadcast() (any thread), drained by one write at a
// time on the loop. A client that does not read keeps one write pending and its queue at its
// limits: frames are dropped, memory stays.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(beast::tcp_stream&& stream, HttpServer::Impl& server, QueueLimits limits)
      : ws_(std::move(stream)), server_(server), queue_(limits) {}

  void start(http::request<http::empty_body> request) {
    request_ = std::move(request);
    beast::get_lowest_layer(ws_).expires_never();  // the WebSocket's own timeouts from here
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, "stride-viz"); }));
    ws_.read_message_max(kWsMessageMax);
    ws_.text(true);
    // A frame is one WebSocket message in one piece: fragments would only cost headers.
    ws_.auto_fragment(false);
    ws_.async_accept(request_, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->open_ = true;
      self->server_.addClient(self);
      self->read();
    });
  }

  void offer(FrameKind kind, FrameText text) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.offer(kind, std::move(text));
    }
    // One wake-up pending at most, whatever the rate of offers.
    if (!kick_.exchange(true))
      asio::post(ws_.get_executor(), [self = shared_from_this()] {
        self->kick_ = false;
        self->writeNext();
      });
  }

  std::uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.dropped();
  }
  std::uint64_t droppedBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.droppedBytes();
  }
  std::size_t queuedBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.bytes();
  }
  std::size_t queuedFrames() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.frames();
  }
  std::uint64_t sent() const { return sent_; }

 private:
  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->closed();
      self->in_.consume(self->in_.size());  // the page has nothing to say: discarded
      self->read();
    });
  }

  void writeNext() {
    if (writing_ || !open_) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      in_flight_ = queue_.pop();
    }
    if (!in_flight_) return;
    writing_ = true;
    ws_.async_write(asio::buffer(*in_flight_),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      self->in_flight_.reset();
                      if (ec) return self->closed();
                      ++self->sent_;
                      ++self->server_.frames_sent;
                      self->writeNext();
                    });
  }

  void closed() {
    if (!open_) return;
    open_ = false;
    server_.removeClient(this);
  }

  websocket::stream<beast::tcp_stream> ws_;
  HttpServer::Impl& server_;
  http::request<http::empty_body> request_;  // the upgrade, until the handshake is done
  beast::flat_buffer in_;
  mutable std::mutex mutex_;  // guards queue_
  ClientQueue queue_;
  std::atomic<bool> kick_{false};
  // The loop's alone:
  bool open_ = false, writing_ = false;
  FrameText in_flight_;
  std::atomic<std::uint64_t> sent_{0};
};

// One HTTP connection: requests one after the other (keep-alive), until the peer closes, a
// request fails to parse (400, then closed), a WebSocket upgrade takes the connection over, or
// nothing comes for kReadTimeout.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, HttpServer::Impl& server)
      : stream_(std::move(socket)), server_(server) {
    ++server_.connections;
  }
  ~HttpSession() { --server_.connections; }

  void start() { read(); }

 private:
  void read() {
    parser_.emplace();
    parser_->header_limit(kHeaderLimit);
    stream_.expires_after(kReadTimeout);
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onRead(ec); });
  }

  void onRead(beast::error_code ec) {
    if (ec == http::error::end_of_stream) return shutdown();
    if (ec && isHttpError(ec)) {
      // What Beast could not parse (garbage, no version, a header over the limit, a body on a
      // GET): 400, then the connection is closed.
      ++server_.bad_requests;
      keep_alive_ = false;
      head_ = false;
      return text(http::status::bad_request, "bad request: " + ec.message() + "\n");
    }
    if (ec) return;  // timeout, reset: the connection is dropped
    ++server_.requests;
    handle(parser_->release());
  }

  void handle(http::request<http::empty_body> req) {
    keep_alive_ = req.keep_alive();
    head_ = req.method() == http::verb::head;
    version_ = req.version();
    std::string_view target(req.target().data(), req.target().size());
    target = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(req)) {
      if (target != "/ws") return text(http::status::not_found, "no WebSocket here: /ws\n");
      if (server_.clientsFull())
        return text(http::status::service_unavailable, "too many viewers connected\n");
      auto ws = std::make_shared<WsSession>(std::move(stream_), server_, server_.options.queue);
      return ws->start(std::move(req));  // the connection is the WebSocket's now
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      http::response<http::string_body> res{http::status::method_not_allowed, version_};
      res.set(http::field::allow, "GET, HEAD");
      res.set(http::field::content_type, "text/plain; charset=utf-8");
      res.body() = "GET or HEAD only\n";
      return reply(std::move(res));
    }
    route(target);
  }

  void route(std::string_view target) {
    const std::string& web = server_.options.web_dir;
    if (target == "/" || target == "/index.html") {
      const fs::path index = fs::path(web) / "index.html";
      std::error_code ec;
      if (!fs::is_regular_file(index, ec))
        return text(http::status::service_unavailable,
                    "the viewer's page was not built: no " + index.string() +
                        " (build the web bundle, viz/README.md, or pass --web-dir)\n");
      return file(index.string());
    }
    if (target.rfind("/assets/", 0) == 0) {
      const auto rel = safeRelativePath(target);
      if (!rel) return notFound();
      return file((fs::path(web) / *rel).string());
    }
    if (target == "/robot.urdf") {
      std::shared_ptr<const RobotFiles> files;
      {
        std::lock_guard<std::mutex> lock(server_.mutex);
        files = server_.files;
      }
      if (!files)
        return text(http::status::service_unavailable,
                    "the robot is not known yet: stride-viz waits for the controller's "
                    "robot_model_t (or give --robot)\n");
      return text(http::status::ok, files->urdf, "application/xml");
    }
    if (target.rfind("/robot/files/", 0) == 0) return robotFile(target.substr(13));
    if (target == "/api/info")
      return text(http::status::ok,
                  server_.apiInfo().dump(-1, ' ', false, Json::error_handler_t::replace),
                  "application/json");
    if (target == "/api/log") return logDocument();
    if (target == "/ws")
      return text(http::status::upgrade_required, "/ws is a WebSocket: ask for an upgrade\n");
    notFound();
  }

  // "<index>/<basename>": only a file the URDF named, under its own basename.
  void robotFile(std::string_view rest) {
    std::shared_ptr<const RobotFiles> files;
    {
      std::lock_guard<std::mutex> lock(server_.mutex);
      files = server_.files;
    }
    const auto slash = rest.find('/');
    if (!files || slash == std::string_view::npos || slash == 0 || slash > 6) return notFound();
    std::size_t index = 0;
    for (const char c : rest.substr(0, slash)) {
      if (c < '0' || c > '9') return notFound();
      index = index * 10 + static_cast<std::size_t>(c - '0');
    }
    if (index >= files->files.size()) return notFound();
    const RobotFile& f = files->files[index];
    if (rest.substr(slash + 1) != f.url_name || f.path.empty()) return notFound();
    file(f.path);
  }

  void logDocument() {
    std::shared_ptr<const std::string> doc;
    {
      std::lock_guard<std::mutex> lock(server_.mutex);
      doc = server_.log_document;
    }
    if (!doc) return text(http::status::not_found, "live mode: there is no log (see /ws)\n");
    http::response<http::span_body<const char>> res{http::status::ok, version_};
    res.set(http::field::content_type, "application/json");
    res.body() = beast::span<const char>(doc->data(), doc->size());
    reply(std::move(res), doc);  // the document stays alive until written
  }

  void file(const std::string& path) {
    std::error_code fec;
    if (!fs::is_regular_file(path, fec)) return notFound();
    http::response<http::file_body> res{http::status::ok, version_};
    beast::error_code ec;
    res.body().open(path.c_str(), beast::file_mode::scan, ec);
    if (ec) return notFound();
    res.set(http::field::content_type, mimeType(path));
    reply(std::move(res));
  }

  void notFound() { text(http::status::not_found, "not found\n"); }

  void text(http::status status, std::string body, const char* type = "text/plain; charset=utf-8") {
    http::response<http::string_body> res{status, version_};
    res.set(http::field::content_type, type);
    res.body() = std::move(body);
    reply(std::move(res));
  }

  // Headers common to every answer, then the write; HEAD gets the headers only. `keep` holds
  // what the body points into until the write is done.
  template <class Body>
  void reply(http::response<Body>&& res, std::shared_ptr<const void> keep = nullptr) {
    res.set(http::field::server, "stride-viz");
    res.set(http::field::cache_control, "no-cache");
    res.set("X-Content-Type-Options", "nosniff");
    res.keep_alive(keep_alive_);
    res.prepare_payload();
    if (head_) {
      http::response<http::empty_body> headers;
      headers.base() = res.base();
      return write(std::move(headers), nullptr);
    }
    write(std::move(res), std::move(keep));
  }

  template <class Body>
  void write(http::response<Body>&& res, std::shared_ptr<const void> keep) {
    auto message = std::make_shared<http::response<Body>>(std::move(res));
    stream_.expires_after(kWriteTimeout);
    http::async_write(
        stream_, *message,
        [self = shared_from_this(), message, keep](beast::error_code ec, std::size_t) {
          if (ec) return;
          if (message->need_eof()) return self->shutdown();
          self->read();
        });
  }

  void shutdown() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  beast::tcp_stream stream_;
  HttpServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  bool keep_alive_ = false, head_ = false;
  unsigned version_ = 11;
};

HttpServer::Impl::~Impl() {
  // Sessions own sockets of the loop: the list lets go of them here, and the loop, destroyed after
  // every other member, destroys the handlers that still hold sessions (and their sockets).
  std::lock_guard<std::mutex> lock(mutex);
  clients.clear();
}

void HttpServer::Impl::listen() {
  beast::error_code ec;
  const auto address = asio::ip::make_address(options.bind, ec);
  if (ec) throw std::runtime_error("--bind '" + options.bind + "': not an IPv4 or IPv6 address");
  const tcp::endpoint at(address, options.port);
  const std::string where = options.bind + " port " + std::to_string(options.port);
  if (acceptor.open(at.protocol(), ec); ec)
    throw std::runtime_error("cannot open a socket for " + where + ": " + ec.message());
  acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (acceptor.bind(at, ec); ec)
    throw std::runtime_error("cannot bind " + where + ": " + ec.message());
  if (acceptor.listen(asio::socket_base::max_listen_connections, ec); ec)
    throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  endpoint = acceptor.local_endpoint();
}

void HttpServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;  // stopped
    // Beyond the limit a connection is closed at once (the socket goes out of scope): a flood
    // of connections costs a bounded amount of memory.
    if (!ec && connections < options.max_connections)
      std::make_shared<HttpSession>(std::move(socket), *this)->start();
    accept();
  });
}

void HttpServer::Impl::doStop() {
  beast::error_code ignored;
  acceptor.close(ignored);
  signals.cancel(ignored);
  info_timer.cancel();
  stop_timer.cancel();
  ioc.stop();
}

void HttpServer::Impl::armInfoTimer() {
  if (options.info_period <= 0.0) return;
  info_timer.expires_after(std::chrono::duration_cast<asio::steady_timer::duration>(
      std::chrono::duration<double>(options.info_period)));
  info_timer.async_wait([this](beast::error_code ec) {
    if (ec) return;
    std::vector<std::shared_ptr<WsSession>> now;
    {
      std::lock_guard<std::mutex> lock(mutex);
      now = clients;
    }
    for (const auto& c : now) c->offer(FrameKind::Info, infoFrame(*c));
    armInfoTimer();
  });
}

void HttpServer::Impl::addClient(const std::shared_ptr<WsSession>& session) {
  FrameText model_text, terrain_text;
  {
    std::lock_guard<std::mutex> lock(mutex);
    clients.push_back(session);
    model_text = model;
    terrain_text = terrain;
  }
  ++clients_served;
  session->offer(FrameKind::Info, infoFrame(*session));
  if (model_text) session->offer(FrameKind::Model, model_text);
  if (terrain_text) session->offer(FrameKind::Terrain, terrain_text);
}

void HttpServer::Impl::removeClient(const WsSession* session) {
  std::lock_guard<std::mutex> lock(mutex);
  const auto it = std::find_if(clients.begin(), clients.end(),
                               [session](const auto& c) { return c.get() == session; });
  if (it == clients.end()) return;
  dropped_by_gone += (*it)->dropped();
  dropped_bytes_by_gone += (*it)->droppedBytes();
  clients.erase(it);
}

FrameText HttpServer::Impl::infoFrame(const WsSession& session) const {
  Json frame = info;
  frame["type"] = "info";
  frame["dropped_frames"] = session.dropped();
  {
    std::lock_guard<std::mutex> lock(mutex);
    frame["warnings"] = source.value("warnings", Json::array());
  }
  return frameText(frame);
}

ServerCounters HttpServer::Impl::counters() const {
  ServerCounters c;
  c.clients_served = clients_served;
  c.frames_sent = frames_sent;
  c.requests = requests;
  c.bad_requests = bad_requests;
  std::lock_guard<std::mutex> lock(mutex);
  c.frames_dropped = dropped_by_gone;
  c.bytes_dropped = dropped_bytes_by_gone;
  c.clients = clients.size();
  for (const auto& s : clients) {
    c.frames_dropped += s->dropped();
    c.bytes_dropped += s->droppedBytes();
    c.queued_bytes += s->queuedBytes();
  }
  return c;
}

Json HttpServer::Impl::apiInfo() const {
  const ServerCounters c = counters();
  Json out = info;
  Json viewers = Json::array();
  {
    std::lock_guard<std::mutex> lock(mutex);
    out["robot_known"] = files != nullptr;
    out.update(source);
    for (const auto& s : clients)
      viewers.push_back({{"queued_bytes", s->queuedBytes()},
                         {"queued_frames", s->queuedFrames()},
                         {"dropped_frames", s->dropped()},
                         {"sent_frames", s->sent()}});
  }
  out["server"] = {{"clients", c.clients},
                   {"clients_served", c.clients_served},
                   {"frames_sent", c.frames_sent},
                   {"frames_dropped", c.frames_dropped},
                   {"bytes_dropped", c.bytes_dropped},
                   {"queued_bytes", c.queued_bytes},
                   {"queue_limit_bytes", options.queue.max_bytes},
                   {"queue_limit_frames", options.queue.max_frames},
                   {"requests", c.requests},
                   {"bad_requests", c.bad_requests},
                   {"viewers", std::move(viewers)}};
  return out;
}

HttpServer::HttpServer(ServerOptions options, Json info)
    : impl_(std::make_unique<Impl>(std::move(options), std::move(info))) {
  impl_->listen();
}

HttpServer::~HttpServer() = default;

unsigned short HttpServer::port() const {
  return impl_->endpoint.port();
}

std::string HttpServer::url() const {
  const auto address = impl_->endpoint.address();
  const std::string host = address.is_v6() ? "[" + address.to_string() + "]" : address.to_string();
  return "http://" + host + ":" + std::to_string(port()) + "/";
}

void HttpServer::run() {
  Impl& s = *impl_;
  s.accept();
  s.armInfoTimer();
  if (s.options.handle_signals) {
    s.signals.add(SIGINT);
    s.signals.add(SIGTERM);
    s.signals.async_wait([&s](beast::error_code ec, int) {
      if (!ec) s.doStop();
    });
  }
  if (s.options.duration > 0.0) {
    s.stop_timer.expires_after(std::chrono::duration_cast<asio::steady_timer::duration>(
        std::chrono::duration<double>(s.options.duration)));
    s.stop_timer.async_wait([&s](beast::error_code ec) {
      if (!ec) s.doStop();
    });
  }
  s.ioc.run();
}

void HttpServer::stop() {
  asio::post(impl_->ioc, [this] { impl_->doStop(); });
}

void HttpServer::setRobotFiles(std::shared_ptr<const RobotFiles> files) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->files = std::move(files);
}

void HttpServer::setModel(const Json& model) {
  const FrameText text = frameText(model);
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->model = text;
  }
  broadcast(FrameKind::Model, text);
}

void HttpServer::setTerrain(const Json& terrain) {
  const FrameText text = frameText(terrain);
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->terrain = text;
  }
  broadcast(FrameKind::Terrain, text);
}

void HttpServer::setLogDocument(std::shared_ptr<const std::string> document) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->log_document = std::move(document);
}

void HttpServer::setSourceInfo(const Json& source) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->source = source;
}

void HttpServer::broadcast(FrameKind kind, FrameText text) {
  std::vector<std::shared_ptr<WsSession>> now;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    now = impl_->clients;
  }
  for (const auto& c : now) c->offer(kind, text);
}

ServerCounters HttpServer::counters() const {
  return impl_->counters();
}

}  // namespace stride::viz
