// trueaxis::ippdme — an I++ DME client over TCP (Asio): send commands with tags, collect each
// transaction's acknowledgement, data, errors and completion; events (E0000 and daemon reports)
// to a callback; timeouts; reconnect.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "trueaxis/ippdme/protocol.hpp"

namespace trueaxis::ippdme {

struct ClientOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 1294;
  double timeout = 60;  // s: the longest wait for a line of a transaction
  std::string log;      // every line sent and received, with the time (empty: none)
};

// An I++ DME server's address, ipp://HOST:PORT (e.g. ipp://127.0.0.1:1294): its host and port.
// Throws Error saying what is expected.
std::pair<std::string, unsigned short> parse_address(const std::string& address);

struct Transaction {
  Tag tag;
  std::vector<std::string> lines;  // every line of this tag, in order (&, #, !, %)
  std::vector<Response> data;      // its # lines
  std::vector<Response> errors;    // its ! lines
  bool complete = false;           // its % arrived
  // The numbers of the data items, in order (e.g. X(1), Y(2) → 1, 2; scan data as they come).
  std::vector<double> numbers() const;
};

class Client {
 public:
  // Connects; throws Error naming host and port when it cannot.
  explicit Client(ClientOptions options);
  ~Client();
  // Called with each data line of a transaction as it arrives (in the thread that waits), so
  // that a scan's points can be judged while the probe still moves.
  using OnData = std::function<void(const Response& data)>;
  // Sends `command` (a method, e.g. "GoTo(X(10))"; a tag is added) and waits until its
  // transaction completes. Throws Error on a timeout or a lost connection.
  Transaction call(const std::string& command, const OnData& on_data = {});
  // Sends `command` with a new tag (an E tag for the fast queue's commands) without waiting.
  Tag send(const std::string& command);
  // Sends a full line (tag included) without waiting; wait() collects its transaction.
  void send_line(const std::string& line);
  Transaction wait(const Tag& tag, const OnData& on_data = {});
  // Called for E0000 lines and daemon reports (from the reader thread).
  void on_event(std::function<void(const std::string& line)> f);
  // Every line received so far, in order (for logs and recordings).
  std::vector<std::string> received() const;
  void reconnect();
  bool connected() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> p_;
};

}  // namespace trueaxis::ippdme
