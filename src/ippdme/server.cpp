// The I++ DME server over TCP: Asio for the socket, one worker thread for the virtual CMM.
#include "trueaxis/ippdme/server.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <asio.hpp>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <mutex>
#include <thread>

#include "trueaxis/error.hpp"

namespace trueaxis::ippdme {

using asio::ip::tcp;

namespace {

struct Conn {
  explicit Conn(tcp::socket s) : sock(std::move(s)) {}
  tcp::socket sock;
  std::array<char, 1 << 16> buf{};
  std::string line;
  bool overlong = false;
  std::deque<std::string> out;  // lines waiting, with CR LF
  std::size_t out_bytes = 0;
  std::string writing_buf;
  bool writing = false, closed = false;
};

}  // namespace

struct Server::Impl {
  ServerOptions o;
  asio::io_context io;
  tcp::acceptor acceptor{io};
  std::unique_ptr<Engine> engine;
  std::thread worker;
  std::atomic<bool> stopping{false};
  mutable std::mutex m;  // guards current and every connection's output
  std::condition_variable cv;
  std::shared_ptr<Conn> current;
  std::ofstream log;
  std::mutex log_m;
  std::atomic<std::size_t> sessions{0};

  void write_log(const char* what, std::string_view line) {
    if (!log.is_open()) return;
    std::lock_guard lk(log_m);
    const auto now = std::chrono::system_clock::now();
    log << fmt::format("{:%H:%M:%S} {}: {}\n", now, what, line);
    log.flush();
  }

  // From the engine, on the io thread (acknowledgements) or the worker (data, completion).
  // Never blocks: the engine may hold its lock here.
  void send(const std::string& l) {
    write_log("sent", l);
    std::unique_lock lk(m);
    std::shared_ptr<Conn> c = current;
    if (!c || c->closed) return;
    c->out.push_back(l + "\r\n");
    c->out_bytes += l.size() + 2;
    if (!c->writing) asio::post(io, [this, c] { flush(c); });
  }

  // The engine's flow control: a slow reader holds the scan back (on the worker, no lock held).
  void wait_writable() {
    std::unique_lock lk(m);
    std::shared_ptr<Conn> c = current;
    if (!c) return;
    cv.wait(lk, [&] { return c->closed || stopping || c->out_bytes < o.max_buffered; });
  }

  void flush(const std::shared_ptr<Conn>& c) {
    std::unique_lock lk(m);
    if (c->writing || c->closed || c->out.empty()) return;
    c->writing = true;
    c->writing_buf.clear();
    while (!c->out.empty() && c->writing_buf.size() < (1 << 20)) {
      c->writing_buf += c->out.front();
      c->out.pop_front();
    }
    lk.unlock();
    asio::async_write(c->sock, asio::buffer(c->writing_buf),
                      [this, c](const asio::error_code& ec, std::size_t n) {
                        {
                          std::lock_guard lk2(m);
                          c->writing = false;
                          c->out_bytes -= std::min(c->out_bytes, n);
                          cv.notify_all();
                        }
                        if (ec) return gone(c);
                        flush(c);
                      });
  }

  void gone(const std::shared_ptr<Conn>& c) {
    {
      std::lock_guard lk(m);
      if (c->closed) return;
      c->closed = true;
      if (current != c) return;
      current.reset();
      cv.notify_all();
    }
    asio::error_code ignore;
    c->sock.close(ignore);
    engine->disconnect();
    write_log("closed", "the client went away; the session ended");
  }

  void read(const std::shared_ptr<Conn>& c) {
    c->sock.async_read_some(asio::buffer(c->buf),
                            [this, c](const asio::error_code& ec, std::size_t n) {
                              if (ec) return gone(c);
                              for (std::size_t i = 0; i < n; ++i) {
                                const char ch = c->buf[i];
                                if (ch == '\n') {
                                  if (!c->line.empty() && c->line.back() == '\r')
                                    c->line.pop_back();
                                  if (c->overlong) {
                                    engine->refuse_overlong(c->line);
                                  } else {
                                    write_log("received", c->line);
                                    engine->receive(c->line);
                                  }
                                  c->line.clear();
                                  c->overlong = false;
                                } else if (!c->overlong) {
                                  c->line.push_back(ch);
                                  if (c->line.size() > kMaxLine + 1) {
                                    c->overlong = true;
                                    c->line.resize(16);  // keep the start: its tag
                                  }
                                }
                              }
                              read(c);
                            });
  }

  void accept() {
    acceptor.async_accept([this](const asio::error_code& ec, tcp::socket s) {
      if (ec) {
        if (!stopping) accept();
        return;
      }
      auto c = std::make_shared<Conn>(std::move(s));
      bool busy;
      {
        std::lock_guard lk(m);
        busy = current && !current->closed;
        if (!busy) current = c;
      }
      if (busy) {
        const std::string refusal =
            "E0000 ! Error(3, 0008, \"another client holds the session\", \"Protocol error\")\r\n";
        asio::error_code ignore;
        asio::write(c->sock, asio::buffer(refusal), ignore);
        c->sock.shutdown(tcp::socket::shutdown_both, ignore);
        c->sock.close(ignore);
        write_log("refused", "a second client while a session runs");
      } else {
        ++sessions;
        asio::error_code ignore;
        c->sock.set_option(tcp::no_delay(true), ignore);
        if (o.socket_buffer > 0)
          c->sock.set_option(asio::socket_base::send_buffer_size(o.socket_buffer), ignore);
        write_log("connected", c->sock.remote_endpoint(ignore).address().to_string());
        read(c);
      }
      accept();
    });
  }
};

Server::Server(ServerOptions options) : p_(std::make_unique<Impl>()) {
  p_->o = std::move(options);
  if (!p_->o.log.empty()) {
    p_->log.open(p_->o.log);
    if (!p_->log) throw Error(fmt::format("{}: cannot write the session log", p_->o.log));
  }
  p_->engine =
      std::make_unique<Engine>(p_->o.engine, [this](const std::string& l) { p_->send(l); });
  p_->engine->set_flow_control([this] { p_->wait_writable(); });
  try {
    const tcp::endpoint ep(asio::ip::make_address(p_->o.host), p_->o.port);
    p_->acceptor.open(ep.protocol());
    p_->acceptor.set_option(tcp::acceptor::reuse_address(true));
    p_->acceptor.bind(ep);
    p_->acceptor.listen();
  } catch (const std::exception& e) {
    throw Error(fmt::format("cannot listen on {}:{}: {}", p_->o.host, p_->o.port, e.what()));
  }
}

Server::~Server() {
  stop();
  if (p_->worker.joinable()) p_->worker.join();
}

unsigned short Server::port() const {
  return p_->acceptor.local_endpoint().port();
}
std::size_t Server::sessions_served() const {
  return p_->sessions;
}
bool Server::session_active() const {
  std::lock_guard lk(p_->m);
  return p_->current && !p_->current->closed;
}

void Server::run() {
  p_->worker = std::thread([this] {
    while (!p_->stopping) p_->engine->execute_next(true);
  });
  p_->accept();
  p_->io.run();
  p_->stopping = true;
  p_->engine->stop();
  {
    std::lock_guard lk(p_->m);
    p_->cv.notify_all();
  }
  if (p_->worker.joinable()) p_->worker.join();
}

void Server::stop() {
  p_->stopping = true;
  p_->engine->stop();
  {
    std::lock_guard lk(p_->m);
    p_->cv.notify_all();
  }
  p_->io.stop();
}

}  // namespace trueaxis::ippdme
