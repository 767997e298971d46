// The I++ DME server over loopback TCP: NIST's programs through the client give what the
// session core gives in process, and the server survives what clients and networks do.
#include "trueaxis/ippdme/server.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <asio.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "nist.hpp"
#include "serving.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/ippdme/recording.hpp"

namespace trueaxis {
namespace {

namespace fs = std::filesystem;
using namespace ippdme;
using asio::ip::tcp;
using test::kNist;
using test::quick;
using test::Running;
using test::slurp;

// A raw connection for what a well-behaved client would not do.
struct Raw {
  asio::io_context io;
  tcp::socket s{io};
  explicit Raw(unsigned short port) {
    s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  }
  void send(const std::string& bytes) { asio::write(s, asio::buffer(bytes)); }
  // Reads until `n` lines arrived (or the server closes).
  std::vector<std::string> lines(std::size_t n) {
    std::vector<std::string> out;
    std::string cur;
    char c;
    asio::error_code ec;
    while (out.size() < n) {
      if (asio::read(s, asio::buffer(&c, 1), ec) != 1) break;
      if (c == '\n') {
        if (!cur.empty() && cur.back() == '\r') cur.pop_back();
        out.push_back(cur);
        cur.clear();
      } else {
        cur.push_back(c);
      }
    }
    return out;
  }
};

void wait_until(const std::function<bool()>& f) {
  for (int i = 0; i < 5000 && !f(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

TEST(IppServer, EveryNistProgramOverTcpGivesTheSessionCoresAnswers) {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kNist)) {
    if (entry.path().extension() != ".prg") continue;
    const auto name = entry.path().stem().string();
    if (name == "parserCmdErrors" || name == "checkerCmdErrors") continue;
    const auto program = recorded_lines(slurp(entry.path()));
    ServerOptions so = quick();
    so.engine.time_scale = name == "AbortE_TestWhileMoving" ? 0.05 : 0;
    Running r(so);
    Client c(r.client());
    for (std::size_t i = 0; i < program.size(); ++i) {
      c.send_line(program[i]);
      if (i + 1 < program.size() && program[i + 1].find("AbortE") != std::string::npos) continue;
      c.wait(*parse_tag(program[i]));
    }
    // In process, the same program (the worker on its own thread, as the server runs it).
    std::vector<std::string> in_process;
    {
      EngineOptions eo = so.engine;
      std::mutex m;
      Engine e(eo, [&](const std::string& l) {
        std::lock_guard lk(m);
        in_process.push_back(l);
      });
      std::thread w([&] {
        while (e.execute_next(true)) {
        }
      });
      std::size_t seen = 0;
      for (std::size_t i = 0; i < program.size(); ++i) {
        e.receive(program[i]);
        if (i + 1 < program.size() && program[i + 1].find("AbortE") != std::string::npos) continue;
        const std::string done = program[i].substr(0, 5) + " %";
        wait_until([&] {
          std::lock_guard lk(m);
          for (std::size_t k = seen; k < in_process.size(); ++k)
            if (in_process[k] == done) {
              seen = k + 1;
              return true;
            }
          return false;
        });
      }
      e.stop();
      w.join();
    }
    const auto d = compare_structure(in_process, c.received());
    for (const auto& x : d)
      ADD_FAILURE() << name << " " << x.tag << ": in process [" << x.expected << "] over TCP ["
                    << x.got << "]";
    ++files;
  }
  EXPECT_EQ(files, 62);
}

TEST(IppServer, ASecondClientIsRefusedWithoutDisturbingTheFirstAndSoAreHundredMore) {
  Running r;
  Client first(r.client());
  EXPECT_TRUE(first.call("StartSession()").complete);
  for (int i = 0; i < 100; ++i) {
    Raw other(r.server.port());
    const auto l = other.lines(1);
    ASSERT_EQ(l.size(), 1u) << i;
    EXPECT_EQ(l[0],
              "E0000 ! Error(3, 0008, \"another client holds the session\", \"Protocol error\")");
    EXPECT_TRUE(other.lines(1).empty()) << "the server closes the refused connection";
  }
  const auto h = first.call("Home()");
  EXPECT_TRUE(h.complete && h.errors.empty());
  EXPECT_EQ(first.call("IsHomed()").numbers(), std::vector<double>{1});
  EXPECT_EQ(r.server.sessions_served(), 1u);
}

TEST(IppServer, GarbageOverlongAndHalfLinesThenANewClientStartsAfresh) {
  Running r;
  {
    Raw raw(r.server.port());
    raw.send("00001 StartSession()\r\n");
    EXPECT_EQ(raw.lines(2), (std::vector<std::string>{"00001 &", "00001 %"}));
    raw.send("\x01\x02 no tag at all\r\n");
    const auto g = raw.lines(1);
    ASSERT_EQ(g.size(), 1u);
    EXPECT_EQ(g[0].substr(0, 8), "E0000 ! ");
    raw.send("00002 GoTo(X(" + std::string(70000, '1') + "))\r\n");
    const auto o = raw.lines(1);
    ASSERT_EQ(o.size(), 1u);
    EXPECT_NE(o[0].find("0008"), std::string::npos) << o[0];
    EXPECT_EQ(o[0].substr(0, 5), "00002");
    raw.send("00003 ClearAllErrors()\r\n00004 GetDMEVersion()\r\n");
    EXPECT_EQ(raw.lines(5)[3], "00004 # DMEVersion(\"1.4.3\")");
    raw.send("00005 GoTo(X(1");  // half a line, then the client goes
  }
  wait_until([&] { return !r.server.session_active(); });
  Client next(r.client());
  const auto s = next.call("StartSession()");
  EXPECT_TRUE(s.complete);
  EXPECT_TRUE(s.errors.empty()) << "the previous session ended when its client went away";
  EXPECT_EQ(r.server.sessions_served(), 2u);
}

TEST(IppServer, AClientLostMidScanLeavesACleanServer) {
  ServerOptions so = quick();
  so.engine.time_scale = 0.02;
  Running r(so);
  {
    Client c(r.client());
    c.call("StartSession()");
    c.call("Home()");
    // A full turn of a 100 mm circle at 10 mm/s: 31 s of machine time, 0.6 s here.
    c.send_line("00010 ScanOnCircle(0, 0, -50, 50, 0, -50, 0, 0, 1, 360, 0, 0.5)");
    wait_until([&] { return c.received().size() > 3; });
  }
  wait_until([&] { return !r.server.session_active(); });
  Client next(r.client());
  EXPECT_TRUE(next.call("StartSession()").errors.empty());
  EXPECT_TRUE(next.call("GoTo(X(10))").errors.empty());
  EXPECT_EQ(next.call("IsHomed()").numbers(), std::vector<double>{1}) << "homing is kept";
}

TEST(IppServer, ASlowReaderLosesNoScanPoint) {
  ServerOptions so = quick();
  so.max_buffered = 2048;   // a few lines: the scan must wait for the reader
  so.socket_buffer = 4096;  // and the kernel may not hide the slowness
  Running r(so);
  Raw raw(r.server.port());
  raw.send("00001 StartSession()\r\n00002 Home()\r\n00003 OnScanReport(X(), Y())\r\n");
  raw.lines(6);
  raw.send("00004 ScanOnCircle(0, 0, -50, 30, 0, -50, 0, 0, 1, 720, 0, 0.1)\r\n");
  std::vector<double> angle;
  std::string last;
  bool status_seen = false;
  for (int i = 0; i < 100000; ++i) {
    const auto l = raw.lines(1);
    ASSERT_EQ(l.size(), 1u);
    last = l[0];
    // The fast queue is served while the scan waits for this slow reader.
    if (i == 50) raw.send("E0100 GetErrStatusE()\r\n");
    if (last == "E0100 # ErrStatus(0)") status_seen = true;
    if (last == "00004 %") break;
    if (last.substr(0, 7) != "00004 #") continue;
    const auto p = parse_response(last);
    ASSERT_TRUE(p);
    for (std::size_t k = 0; k + 1 < p.value->items.size(); k += 2)
      angle.push_back(std::atan2(p.value->items[k + 1].number(), p.value->items[k].number()));
    if (i % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // slow
  }
  EXPECT_EQ(last, "00004 %");
  for (int i = 0; i < 10 && !status_seen; ++i) {
    const auto l = raw.lines(1);
    status_seen = !l.empty() && l[0] == "E0100 # ErrStatus(0)";
  }
  EXPECT_TRUE(status_seen) << "GetErrStatusE during the held-back scan";
  // Two turns every 0.1°: 7200 points, in order (the angle always advancing).
  EXPECT_GE(angle.size(), 7150u);
  EXPECT_LE(angle.size(), 7250u);
  double turned = 0;
  for (std::size_t k = 1; k < angle.size(); ++k) {
    double d = angle[k] - angle[k - 1];
    if (d < -M_PI) d += 2 * M_PI;
    ASSERT_GT(d, 0) << "point " << k << " out of order";
    turned += d;
  }
  EXPECT_NEAR(turned * 180 / M_PI, 720, 1);
}

TEST(IppServer, AbortEOverTheWireStopsALongGoToAndTheFastQueueAnswersMeanwhile) {
  ServerOptions so = quick();
  so.engine.time_scale = 0.05;
  Running r(so);
  Client c(r.client());
  c.call("StartSession()");
  c.call("Home()");
  c.call("SetProp(Tool.GoToPar.Speed(10))");
  c.send_line("00100 GoTo(X(300))");  // 30 s of machine time, 1.5 s here
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const auto status = c.call("GetErrStatusE()");  // answered while the machine moves
  EXPECT_EQ(status.numbers(), std::vector<double>{0});
  const auto speed = c.call("GetPropE(Tool.GoToPar.Speed())");
  EXPECT_EQ(speed.numbers(), std::vector<double>{10});
  const auto abort = c.call("AbortE()");
  EXPECT_TRUE(abort.complete);
  const auto go = c.wait(Tag{false, 100});
  ASSERT_EQ(go.errors.size(), 1u);
  EXPECT_EQ(go.errors[0].items[0].args[1].text, "0006");
  EXPECT_EQ(c.call("Get(X())").errors.size(), 1u) << "0514 until ClearAllErrors";
  c.call("ClearAllErrors()");
  const auto x = c.call("Get(X())").numbers();
  ASSERT_EQ(x.size(), 1u);
  EXPECT_GT(x[0], 0.5);
  EXPECT_LT(x[0], 100) << "stopped long before the target";
}

TEST(IppServer, AClientWithNoServerSaysWhere) {
  ClientOptions c;
  c.port = 1;  // nothing listens there
  try {
    Client x(c);
    FAIL() << "connected to nothing";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace trueaxis
