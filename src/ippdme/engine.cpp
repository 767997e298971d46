// The I++ DME server's session core: commands in, responses out, against the virtual CMM.
#include "trueaxis/ippdme/engine.hpp"

#include <fmt/format.h>

#include <chrono>
#include <thread>

#include "engine_state.hpp"

namespace trueaxis::ippdme {

// ---- the engine ----------------------------------------------------------------------------

Engine::Engine(EngineOptions options, Send send)
    : s_(std::make_unique<State>(std::move(options), std::move(send))) {}

Engine::~Engine() = default;

const SimulatedCmm& Engine::cmm() const {
  return s_->cmm;
}
double Engine::machine_time() const {
  return s_->cmm.time();
}

void Engine::receive(std::string_view text) {
  State& s = *s_;
  std::unique_lock lk(s.m);
  if (text.size() > kMaxLine) {
    s.error(parse_tag(text).value_or(Tag{true, 0}), 8, "line longer than 65536 characters");
    return;
  }
  auto parsed = parse_command(text);
  std::optional<SyntaxError> bad;
  if (!parsed)
    bad = parsed.error;
  else
    bad = check(*parsed.value);
  // A fast-queue command with an ordinary tag (error 0001 of the check) runs all the same,
  // reported on E0000 below.
  if (bad && parsed && bad->error == 1 && is_event_command(parsed.value->method.text) &&
      !parsed.value->tag.event)
    bad.reset();
  if (bad) {
    // The cause names the column and the reason, e.g. "column 18: GoTo: X is given twice".
    const Tag t = parsed ? parsed.value->tag : parse_tag(text).value_or(Tag{true, 0});
    const bool tagged = !(t.event && t.number == 0);
    if (tagged) s.line(t, '&');
    s.error(t, bad->error, fmt::format("column {}: {}", bad->column, bad->what));
    if (tagged) s.line(t, '%');
    return;
  }
  Command c = std::move(*parsed.value);
  const std::string& n = c.method.text;
  s.line(c.tag, '&');
  if (!is_event_command(n)) {
    s.queue.push_back(std::move(c));
    s.cv.notify_all();
    return;
  }
  // The fast queue, whatever the tag. A command sent with an ordinary tag is reported on
  // E0000 (error 0001, which stops nothing here: the command runs), and its completion waits
  // for the transactions before it, so that a '%' never comes before an earlier one's.
  const bool ordinary = !c.tag.event;
  if (ordinary)
    s.error(Tag{true, 0}, 1,
            fmt::format("{} with tag {}: a fast-queue command, run at once", n, c.tag.text()),
            false);
  auto complete = [&] {
    if (ordinary && (s.running || !s.queue.empty())) {
      Command done;
      done.tag = c.tag;
      done.method.text = kCompletion;
      s.queue.push_back(std::move(done));
      s.cv.notify_all();
      return;
    }
    s.line(c.tag, '%');
  };
  if (n == "AbortE") {
    if (!s.running && s.queue.empty()) {
      if (s.session) s.latched = 6;
      complete();
      return;
    }
    s.abort_tag = c.tag;
    s.abort = true;
    s.daemons.clear();  // a daemon is a transaction too: AbortE ends it
    s.cv.notify_all();
    return;
  }
  if (!s.session) {
    s.error(c.tag, 8, n);
    complete();
    return;
  }
  try {
    if (n == "GetErrStatusE") {
      s.data(c.tag, {call("ErrStatus", {number(s.latched ? 1 : 0)})});
    } else if (n == "GetPropE") {
      std::vector<Value> out;
      for (const auto& a : c.method.args) out.push_back(s.get_property(a));
      s.data(c.tag, out);
    } else if (n == "OnMoveReportE") {
      Daemon d;
      d.tag = c.tag;
      for (const auto& a : c.method.args) {
        if (a.is_call("Time"))
          d.every = a.args.at(0).number();
        else if (a.is_call("Dis"))
          d.dis = a.args.at(0).number();
        else
          d.items.push_back(a.text);
      }
      // Time at least 0.1 s and a positive distance (6.3.2.7), one daemon at a time (0515, as
      // NIST's checker: stop it before starting another).
      for (const auto& a : c.method.args)
        if ((a.is_call("Time") && !(a.args.at(0).number() >= 0.1)) ||
            (a.is_call("Dis") && !(a.args.at(0).number() > 0)))
          throw Fail{510};
      if (std::any_of(s.daemons.begin(), s.daemons.end(),
                      [&](const Daemon& e) { return !(e.tag == d.tag); }))
        throw Fail{515};
      s.daemons.erase(std::remove_if(s.daemons.begin(), s.daemons.end(),
                                     [&](const Daemon& e) { return e.tag == d.tag; }),
                      s.daemons.end());
      s.daemons.push_back(d);
      complete();
      // The first report tells where the machine is now.
      s.report_move(s.daemons.back(), true);
      return;
    }
  } catch (const Fail& f) {
    s.error(c.tag, f.number, n);
  }
  complete();
}

void Engine::refuse_overlong(std::string_view start) {
  std::lock_guard lk(s_->m);
  s_->error(parse_tag(start).value_or(Tag{true, 0}), 8, "line longer than 65536 characters");
}

bool Engine::execute_next(bool wait) {
  State& s = *s_;
  std::unique_lock lk(s.m);
  if (wait) s.cv.wait(lk, [&] { return s.stopping || !s.queue.empty() || s.abort_tag; });
  auto finish_abort = [&] {
    if (!s.abort_tag) return;
    for (const auto& q : s.queue) {
      if (q.method.text != kCompletion) s.error(q.tag, 6, q.method.text);
      s.line(q.tag, '%');
    }
    s.queue.clear();
    s.line(*s.abort_tag, '%');
    s.abort_tag.reset();
    s.abort = false;
    if (s.session) s.latched = 6;
  };
  if (s.queue.empty()) {
    finish_abort();
    return false;
  }
  const Command c = std::move(s.queue.front());
  s.queue.pop_front();
  if (c.method.text == kCompletion) {
    // A fast-queue command's completion, in its turn.
    s.line(c.tag, '%');
    finish_abort();
    s.cv.notify_all();
    return true;
  }
  s.running = true;
  s.pace_start();
  try {
    Executor(s, lk, c).run();
  } catch (const Stopped&) {
    s.error(c.tag, 6, c.method.text);
  } catch (const Fail& f) {
    s.error(c.tag, f.number, c.method.text);
  } catch (const std::exception&) {
    s.error(c.tag, 511, c.method.text);
  }
  if (!s.abort_tag) s.abort = false;  // a stop for a client that went away
  s.line(c.tag, '%');
  s.running = false;
  finish_abort();
  // Behind an error the pending transactions are aborted, up to one that may run in the error
  // state.
  while (s.latched && s.latched != 6 && !s.queue.empty()) {
    const Command& q = s.queue.front();
    const std::string& n = q.method.text;
    if (n == "ClearAllErrors" || n == "EndSession" || n == "GetXtdErrStatus") break;
    if (n != kCompletion) s.error(q.tag, 6, n);
    s.line(q.tag, '%');
    s.queue.pop_front();
  }
  s.cv.notify_all();  // disconnect() waits for the command to end
  return true;
}

void Engine::drain() {
  while (execute_next(false)) {
  }
}

void Engine::disconnect() {
  State& s = *s_;
  {
    std::lock_guard lk(s.m);
    s.queue.clear();
    s.daemons.clear();
    if (s.running) s.abort = true;
  }
  // Wait for a running command to stop (the worker clears `running` and notifies).
  std::unique_lock lk(s.m);
  s.cv.wait(lk, [&] { return !s.running; });
  s.abort = false;
  s.abort_tag.reset();
  s.session = false;
  s.latched = 0;
}

void Engine::set_flow_control(std::function<void()> wait_until_writable) {
  std::lock_guard lk(s_->m);
  s_->flow = std::move(wait_until_writable);
}

void Engine::stop() {
  std::lock_guard lk(s_->m);
  s_->stopping = true;
  s_->cv.notify_all();
}

}  // namespace trueaxis::ippdme
