// A test I++ DME server on its own thread, on any free port.
#pragma once

#include <thread>

#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/ippdme/server.hpp"

namespace trueaxis::test {

// Options for a test server: any free port, the machine as fast as it computes.
inline ippdme::ServerOptions quick() {
  ippdme::ServerOptions o;
  o.port = 0;
  o.engine.time_scale = 0;
  return o;
}

// A server running on its own thread until the end of the scope.
struct Running {
  ippdme::Server server;
  std::thread t;
  explicit Running(const ippdme::ServerOptions& o = quick())
      : server(o), t([this] { server.run(); }) {}
  ~Running() {
    server.stop();
    t.join();
  }
  ippdme::ClientOptions client() const {
    ippdme::ClientOptions c;
    c.port = server.port();
    c.timeout = 30;
    return c;
  }
};

}  // namespace trueaxis::test
