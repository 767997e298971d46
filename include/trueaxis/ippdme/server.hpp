// trueaxis::ippdme — the I++ DME server over TCP (Asio): one session at a time, the virtual CMM
// behind it (engine.hpp).
//
// Lines end in CR LF (a bare LF is accepted too). A line longer than the specification's 65 536
// characters is answered with error 0008 and skipped up to its end. A second client is told
// `E0000 ! Error(3, 0008, "another client holds the session", "Protocol error")` and closed;
// the first is not disturbed. When the client goes away (even mid-scan or mid-move), the motion
// stops, queued commands and daemons are dropped and the session ends: the next client starts
// afresh (tools, coordinate systems and the homed state are kept, as the specification says).
//
// Responses are written as fast as the client reads; a client that reads slowly holds the
// scan back (at most `max_buffered` bytes wait), so no point is lost.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "trueaxis/ippdme/engine.hpp"

namespace trueaxis::ippdme {

struct ServerOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 1294;  // 0: any free port (see Server::port)
  EngineOptions engine;
  std::string log;  // a session log: every line received and sent, with the time (empty: none)
  std::size_t max_buffered = 4 << 20;  // bytes of responses waiting for a slow client
  int socket_buffer = 0;               // the sockets' kernel send buffer (bytes; 0: the system's)
};

class Server {
 public:
  // Binds the port (throws Error naming host and port if it cannot).
  explicit Server(ServerOptions options);
  ~Server();
  unsigned short port() const;  // the port bound
  // Serves until stop(); on the calling thread (plus one worker thread for the machine).
  void run();
  void stop();                          // from any thread
  std::size_t sessions_served() const;  // clients connected so far
  bool session_active() const;          // a client is connected

  struct Impl;

 private:
  std::unique_ptr<Impl> p_;
};

}  // namespace trueaxis::ippdme
