// The I++ DME server over loopback TCP, against plain loopback TCP in the same run:
// - scan points streamed: a ScanOnCircle at 100 mm/s, a point every 0.2° of a Ø100 mm circle
//   (1 800 points of X, Y, Z, IJK), read by a client, against the same number of bytes sent
//   through a plain loopback socket;
// - a command's round trip (Get(X()) through the client library: & # %) against a TCP echo of
//   one line.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <asio.hpp>
#include <memory>
#include <string>
#include <thread>

#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/ippdme/server.hpp"

namespace {

using namespace trueaxis;
using asio::ip::tcp;

struct Served {
  std::unique_ptr<ippdme::Server> server;
  std::thread t;
  Served() {
    ippdme::ServerOptions o;
    o.port = 0;
    o.engine.time_scale = 0;  // as fast as the simulation computes
    server = std::make_unique<ippdme::Server>(o);
    t = std::thread([this] { server->run(); });
  }
  ~Served() {
    server->stop();
    t.join();
  }
};

// Reads lines from a socket until one equals `last`; returns the bytes read. Counts the
// numbers on data lines.
std::size_t read_until_line(tcp::socket& s, const std::string& last, std::string& buf,
                            long* numbers) {
  std::size_t total = 0;
  char chunk[1 << 16];
  for (;;) {
    const auto nl = buf.find('\n');
    if (nl != std::string::npos) {
      const std::string line = buf.substr(0, nl > 0 && buf[nl - 1] == '\r' ? nl - 1 : nl);
      buf.erase(0, nl + 1);
      if (numbers && line.size() > 6 && line[6] == '#')
        *numbers += 1 + static_cast<long>(std::count(line.begin(), line.end(), ','));
      if (line == last) return total;
      continue;
    }
    const std::size_t n = s.read_some(asio::buffer(chunk));
    total += n;
    buf.append(chunk, n);
  }
}

void BM_IppScanPointsOverLoopback(benchmark::State& st) {
  Served srv;
  asio::io_context io;
  tcp::socket s(io);
  s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), srv.server->port()));
  std::string buf;
  asio::write(s, asio::buffer(std::string("00001 StartSession()\r\n00002 Home()\r\n"
                                          "00003 OnScanReport(X(), Y(), Z(), IJK())\r\n"
                                          "00004 SetProp(Tool.ScanPar.Speed(100))\r\n")));
  read_until_line(s, "00004 %", buf, nullptr);
  std::size_t bytes = 0;
  long numbers = 0;
  for (auto _ : st) {
    asio::write(s, asio::buffer(std::string(
                       "00010 ScanOnCircle(0, 0, -50, 50, 0, -50, 0, 0, 1, 360, 0, 0.2)\r\n")));
    bytes += read_until_line(s, "00010 %", buf, &numbers);
  }
  const double points = static_cast<double>(numbers) / 6;
  st.counters["points/s"] = benchmark::Counter(points, benchmark::Counter::kIsRate);
  st.counters["points"] = points / static_cast<double>(st.iterations());
  st.SetBytesProcessed(static_cast<std::int64_t>(bytes));
}
BENCHMARK(BM_IppScanPointsOverLoopback)->Unit(benchmark::kMillisecond)->UseRealTime();

// The baseline: the bytes of one such scan (1 800 points of six 5-decimal numbers, 16 points a
// line) through a plain loopback socket.
void BM_IppPlainLoopbackStream(benchmark::State& st) {
  asio::io_context io;
  tcp::acceptor acc(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  const std::size_t size = 1800 * 6 * 11 + 113 * 8;
  std::thread sender([&] {
    tcp::socket out(io);
    acc.accept(out);
    const std::string block(size, 'x');
    char go;
    asio::error_code ec;
    while (asio::read(out, asio::buffer(&go, 1), ec) == 1 && go == 'g')
      asio::write(out, asio::buffer(block), ec);
  });
  tcp::socket in(io);
  in.connect(acc.local_endpoint());
  std::vector<char> buf(1 << 16);
  for (auto _ : st) {
    asio::write(in, asio::buffer("g", 1));
    std::size_t got = 0;
    while (got < size) got += in.read_some(asio::buffer(buf));
  }
  asio::write(in, asio::buffer("q", 1));
  sender.join();
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations() * size));
}
BENCHMARK(BM_IppPlainLoopbackStream)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IppCommandRoundTrip(benchmark::State& st) {
  Served srv;
  ippdme::ClientOptions co;
  co.port = srv.server->port();
  ippdme::Client c(co);
  c.call("StartSession()");
  for (auto _ : st) benchmark::DoNotOptimize(c.call("Get(X())"));
}
BENCHMARK(BM_IppCommandRoundTrip)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The baseline: one line sent and echoed back over loopback TCP (TCP_NODELAY both ways).
void BM_IppTcpEchoRoundTrip(benchmark::State& st) {
  asio::io_context io;
  tcp::acceptor acc(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  std::thread echo([&] {
    tcp::socket s(io);
    acc.accept(s);
    s.set_option(tcp::no_delay(true));
    char buf[256];
    asio::error_code ec;
    for (;;) {
      const std::size_t n = s.read_some(asio::buffer(buf), ec);
      if (ec || (n == 1 && buf[0] == 'q')) return;
      asio::write(s, asio::buffer(buf, n), ec);
    }
  });
  tcp::socket s(io);
  s.connect(acc.local_endpoint());
  s.set_option(tcp::no_delay(true));
  const std::string line = "00005 Get(X())\r\n";
  char buf[256];
  for (auto _ : st) {
    asio::write(s, asio::buffer(line));
    std::size_t got = 0;
    while (got < line.size()) got += s.read_some(asio::buffer(buf));
  }
  asio::write(s, asio::buffer("q", 1));
  echo.join();
}
BENCHMARK(BM_IppTcpEchoRoundTrip)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace
