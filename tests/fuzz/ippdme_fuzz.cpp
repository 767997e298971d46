// libFuzzer target: the I++ DME line parser on arbitrary bytes, as command and as response. A
// parse must end in a value or a syntax error, never throw; whatever parses formats back to the
// same characters and parses again to the same text; the command checks never throw either.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "trueaxis/ippdme/commands.hpp"
#include "trueaxis/ippdme/protocol.hpp"

using namespace trueaxis;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  if (const auto c = ippdme::parse_command(line)) {
    const std::string back = ippdme::format(*c.value);
    if (back != line) std::abort();
    const auto again = ippdme::parse_command(back);
    if (!again || ippdme::format(*again.value) != back) std::abort();
    if (const auto e = ippdme::check(*c.value); e && (e->column == 0 || e->what.empty()))
      std::abort();
  } else if (c.error.column == 0 || c.error.what.empty()) {
    std::abort();
  }
  if (const auto r = ippdme::parse_response(line)) {
    if (ippdme::format(*r.value) != line) std::abort();
    if (const auto e = ippdme::check(*r.value); e && e->what.empty()) std::abort();
  } else if (r.error.column == 0 || r.error.what.empty()) {
    std::abort();
  }
  return 0;
}
