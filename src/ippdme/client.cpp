// An I++ DME client over TCP: a reader thread collects lines per tag; calls wait for them.
#include "trueaxis/ippdme/client.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <asio.hpp>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "trueaxis/error.hpp"
#include "trueaxis/ippdme/commands.hpp"

namespace trueaxis::ippdme {

std::pair<std::string, unsigned short> parse_address(const std::string& address) {
  const std::string scheme = "ipp://";
  const auto bad = [&] {
    return Error(
        fmt::format("'{}' is not an I++ DME server address: expected ipp://HOST:PORT, e.g. "
                    "ipp://127.0.0.1:1294",
                    address));
  };
  if (address.rfind(scheme, 0) != 0) throw bad();
  const std::string rest = address.substr(scheme.size());
  const auto colon = rest.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == rest.size()) throw bad();
  const std::string port = rest.substr(colon + 1);
  if (port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) throw bad();
  const long p = std::stol(port);
  if (p < 1 || p > 65535) throw bad();
  return {rest.substr(0, colon), static_cast<unsigned short>(p)};
}

using asio::ip::tcp;

std::vector<double> Transaction::numbers() const {
  std::vector<double> v;
  for (const auto& d : data)
    for (const auto& it : d.items) {
      if (it.kind == Value::Kind::Number) v.push_back(it.number());
      for (const auto& a : it.args)
        if (a.kind == Value::Kind::Number) v.push_back(a.number());
    }
  return v;
}

struct Client::Impl {
  ClientOptions o;
  asio::io_context io;
  std::unique_ptr<tcp::socket> sock;
  std::thread reader;
  mutable std::mutex m;
  std::condition_variable cv;
  std::map<std::string, std::deque<std::string>> by_tag;  // lines not yet collected
  std::vector<std::string> all;
  std::set<std::string> complete_e;  // E tags whose transaction completed (later #: events)
  std::function<void(const std::string&)> event;
  bool up = false;
  int next = 0, next_e = 0;
  std::ofstream log;
  std::mutex log_m;

  void write_log(const char* what, std::string_view l) {
    if (!log.is_open()) return;
    std::lock_guard lk(log_m);
    log << fmt::format("{:%H:%M:%S} {}: {}\n", std::chrono::system_clock::now(), what, l);
    log.flush();
  }

  void connect() {
    sock = std::make_unique<tcp::socket>(io);
    try {
      tcp::resolver r(io);
      asio::connect(*sock, r.resolve(o.host, std::to_string(o.port)));
      sock->set_option(tcp::no_delay(true));
    } catch (const std::exception& e) {
      throw Error(fmt::format("cannot connect to an I++ DME server at {}:{}: {}", o.host, o.port,
                              e.what()));
    }
    {
      std::lock_guard lk(m);
      up = true;
    }
    reader = std::thread([this] { read_loop(); });
  }

  void read_loop() {
    std::string line, chunk(1 << 16, '\0');
    for (;;) {
      asio::error_code ec;
      const std::size_t n = sock->read_some(asio::buffer(chunk), ec);
      if (ec) break;
      for (std::size_t i = 0; i < n; ++i) {
        if (chunk[i] != '\n') {
          line.push_back(chunk[i]);
          continue;
        }
        if (!line.empty() && line.back() == '\r') line.pop_back();
        deliver(line);
        line.clear();
      }
    }
    std::lock_guard lk(m);
    up = false;
    cv.notify_all();
  }

  void deliver(const std::string& l) {
    write_log("received", l);
    const std::string tag = l.substr(0, std::min<std::size_t>(5, l.size()));
    std::function<void(const std::string&)> f;
    {
      std::lock_guard lk(m);
      all.push_back(l);
      const bool is_event =
          tag == "E0000" || (tag[0] == 'E' && complete_e.count(tag) && l.size() > 6 && l[6] == '#');
      if (is_event) {
        f = event;
      } else {
        by_tag[tag].push_back(l);
        if (tag[0] == 'E' && l.size() > 6 && l[6] == '%') complete_e.insert(tag);
      }
      cv.notify_all();
    }
    if (f) f(l);
  }

  void close() {
    if (sock) {
      asio::error_code ignore;
      sock->shutdown(tcp::socket::shutdown_both, ignore);
      sock->close(ignore);
    }
    if (reader.joinable()) reader.join();
  }
};

Client::Client(ClientOptions options) : p_(std::make_unique<Impl>()) {
  p_->o = std::move(options);
  if (!p_->o.log.empty()) {
    p_->log.open(p_->o.log);
    if (!p_->log) throw Error(fmt::format("{}: cannot write the session log", p_->o.log));
  }
  p_->connect();
}

Client::~Client() {
  p_->close();
}

void Client::on_event(std::function<void(const std::string&)> f) {
  std::lock_guard lk(p_->m);
  p_->event = std::move(f);
}

std::vector<std::string> Client::received() const {
  std::lock_guard lk(p_->m);
  return p_->all;
}

bool Client::connected() const {
  std::lock_guard lk(p_->m);
  return p_->up;
}

void Client::reconnect() {
  p_->close();
  {
    std::lock_guard lk(p_->m);
    p_->by_tag.clear();
    p_->complete_e.clear();
  }
  p_->connect();
}

void Client::send_line(const std::string& line) {
  {
    std::lock_guard lk(p_->m);
    if (!p_->up) throw Error("I++ DME: the connection to the server is closed");
    const std::string tag = line.substr(0, std::min<std::size_t>(5, line.size()));
    p_->by_tag.erase(tag);
    p_->complete_e.erase(tag);
  }
  p_->write_log("sent", line);
  asio::error_code ec;
  asio::write(*p_->sock, asio::buffer(line + "\r\n"), ec);
  if (ec) throw Error(fmt::format("I++ DME: cannot send to the server: {}", ec.message()));
}

Transaction Client::wait(const Tag& tag, const OnData& on_data) {
  const std::string t = tag.text();
  Transaction tr;
  tr.tag = tag;
  std::unique_lock lk(p_->m);
  for (;;) {
    auto& q = p_->by_tag[t];
    while (!q.empty()) {
      const std::string l = std::move(q.front());
      q.pop_front();
      tr.lines.push_back(l);
      if (const auto r = parse_response(l)) {
        if (r.value->kind == Response::Kind::Data) {
          tr.data.push_back(*r.value);
          if (on_data) {
            lk.unlock();
            on_data(*r.value);
            lk.lock();
          }
        }
        if (r.value->kind == Response::Kind::Error) tr.errors.push_back(*r.value);
        if (r.value->kind == Response::Kind::Done) tr.complete = true;
      }
      if (tr.complete) return tr;
    }
    if (!p_->up) throw Error(fmt::format("I++ DME: the server closed the connection ({})", t));
    if (!p_->cv.wait_for(lk, std::chrono::duration<double>(p_->o.timeout),
                         [&] { return !p_->by_tag[t].empty() || !p_->up; }))
      throw Error(fmt::format("I++ DME: no answer to {} within {:g} s", t, p_->o.timeout));
  }
}

Tag Client::send(const std::string& command) {
  const auto open = command.find('(');
  const bool fast = is_event_command(command.substr(0, open));
  Tag tag;
  {
    std::lock_guard lk(p_->m);
    tag = fast ? Tag{true, 1 + (p_->next_e++ % 9999)} : Tag{false, 1 + (p_->next++ % 99999)};
  }
  send_line(tag.text() + " " + command);
  return tag;
}

Transaction Client::call(const std::string& command, const OnData& on_data) {
  return wait(send(command), on_data);
}

}  // namespace trueaxis::ippdme
