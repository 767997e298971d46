// NIST-form programs and recordings; response streams compared by structure.
#include "trueaxis/ippdme/recording.hpp"

#include <fmt/format.h>

#include <map>
#include <set>

#include "trueaxis/ippdme/protocol.hpp"

namespace trueaxis::ippdme {

std::vector<std::string> recorded_lines(std::string_view text, std::vector<long>* numbers) {
  std::vector<std::string> out;
  std::size_t a = 0;
  long number = 0;
  while (a < text.size()) {
    std::size_t b = text.find('\n', a);
    if (b == std::string_view::npos) b = text.size();
    std::string_view l = text.substr(a, b - a);
    a = b + 1;
    ++number;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    if (l.empty() || l == "\\\\" || l.front() == ':') continue;
    out.emplace_back(l);
    if (numbers) numbers->push_back(number);
  }
  return out;
}

namespace {

bool bare_numbers(const Response& r) {
  if (r.items.empty()) return false;
  for (const auto& v : r.items)
    if (v.kind != Value::Kind::Number) return false;
  return true;
}

// Tag → the tokens of its lines.
std::map<std::string, std::vector<std::string>> tokens(const std::vector<std::string>& lines) {
  std::map<std::string, std::vector<std::string>> out;
  std::set<std::string> complete;  // E tags whose transaction completed (later # are events)
  for (const auto& l : lines) {
    const auto p = parse_response(l);
    const std::string tag = l.substr(0, std::min<std::size_t>(5, l.size()));
    if (tag == "E0000") continue;
    auto& t = out[tag];
    if (!p) {
      t.push_back("?");
      continue;
    }
    const Response& r = *p.value;
    switch (r.kind) {
      case Response::Kind::Ack:
        t.push_back("&");
        break;
      case Response::Kind::Done:
        t.push_back("%");
        if (r.tag.event) complete.insert(tag);
        break;
      case Response::Kind::Error: {
        const auto& e = r.items.at(0);
        t.push_back(e.args.size() > 1 && e.args[1].kind == Value::Kind::Number
                        ? fmt::format("!{:04.0f}", e.args[1].number())
                        : std::string("!?"));
        break;
      }
      case Response::Kind::Data:
        if (r.tag.event && complete.count(tag)) break;  // a daemon's report
        if (bare_numbers(r)) {
          if (t.empty() || t.back() != "#scan") t.push_back("#scan");
        } else {
          t.push_back(fmt::format("#{}", r.items.size()));
        }
        break;
    }
  }
  return out;
}

std::string join(const std::vector<std::string>& t) {
  std::string s;
  for (const auto& x : t) {
    if (!s.empty()) s += ' ';
    s += x;
  }
  return s.empty() ? "-" : s;
}

}  // namespace

std::string structure(const std::vector<std::string>& lines, const std::string& tag) {
  const auto t = tokens(lines);
  const auto it = t.find(tag);
  return it == t.end() ? "-" : join(it->second);
}

std::vector<StructureDifference> compare_structure(const std::vector<std::string>& expected,
                                                   const std::vector<std::string>& got) {
  const auto e = tokens(expected), g = tokens(got);
  std::set<std::string> tags;
  for (const auto& [k, v] : e) tags.insert(k);
  for (const auto& [k, v] : g) tags.insert(k);
  std::vector<StructureDifference> out;
  for (const auto& tag : tags) {
    const auto ei = e.find(tag), gi = g.find(tag);
    const std::string es = ei == e.end() ? "-" : join(ei->second);
    const std::string gs = gi == g.end() ? "-" : join(gi->second);
    if (es != gs) out.push_back({tag, es, gs});
  }
  return out;
}

}  // namespace trueaxis::ippdme
