#include "trueaxis/io/units.hpp"

#include <fmt/format.h>

#include <array>
#include <cctype>

#include "fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

struct UnitInfo {
  Unit unit;
  UnitKind kind;
  double scale;  // value in the kind's base unit (mm, rad, s, °C, 1) per unit
  std::string_view symbol;
};

constexpr double kPi = 3.14159265358979323846;
constexpr std::array<UnitInfo, 15> kUnitTable{{
    {Unit::Metre, UnitKind::Length, 1e3, "m"},
    {Unit::Millimetre, UnitKind::Length, 1, "mm"},
    {Unit::Micrometre, UnitKind::Length, 1e-3, "\xC2\xB5m"},
    {Unit::Nanometre, UnitKind::Length, 1e-6, "nm"},
    {Unit::Inch, UnitKind::Length, 25.4, "in"},
    {Unit::Radian, UnitKind::Angle, 1, "rad"},
    {Unit::Milliradian, UnitKind::Angle, 1e-3, "mrad"},
    {Unit::Microradian, UnitKind::Angle, 1e-6, "\xC2\xB5rad"},
    {Unit::Degree, UnitKind::Angle, kPi / 180, "\xC2\xB0"},
    {Unit::Arcsecond, UnitKind::Angle, kPi / 648000, "arcsec"},
    {Unit::Second, UnitKind::Time, 1, "s"},
    {Unit::Millisecond, UnitKind::Time, 1e-3, "ms"},
    {Unit::Minute, UnitKind::Time, 60, "min"},
    {Unit::Celsius, UnitKind::Temperature, 1,
     "\xC2\xB0"
     "C"},
    {Unit::Count, UnitKind::Count, 1, ""},
}};

const UnitInfo& info(Unit u) {
  for (const UnitInfo& i : kUnitTable)
    if (i.unit == u) return i;
  throw Error("unknown unit");  // unreachable: every enumerator is in the table
}

// Spellings of each unit, in lower case; the micro sign may be U+00B5, Greek mu U+03BC or "u".
struct Spelling {
  std::string_view text;
  Unit unit;
};
constexpr std::array<Spelling, 30> kUnitSpellings{{
    {"m", Unit::Metre},
    {"mm", Unit::Millimetre},
    {"um", Unit::Micrometre},
    {"micron", Unit::Micrometre},
    {"microns", Unit::Micrometre},
    {"nm", Unit::Nanometre},
    {"in", Unit::Inch},
    {"inch", Unit::Inch},
    {"rad", Unit::Radian},
    {"mrad", Unit::Milliradian},
    {"urad", Unit::Microradian},
    {"deg", Unit::Degree},
    {"degree", Unit::Degree},
    {"degrees", Unit::Degree},
    {"\xC2\xB0", Unit::Degree},
    {"arcsec", Unit::Arcsecond},
    {"\"", Unit::Arcsecond},
    {"s", Unit::Second},
    {"sec", Unit::Second},
    {"ms", Unit::Millisecond},
    {"min", Unit::Minute},
    {"c", Unit::Celsius},
    {"\xC2\xB0"
     "c",
     Unit::Celsius},
    {"degc", Unit::Celsius},
    {"deg c", Unit::Celsius},
    {"\xE2\x84\x83", Unit::Celsius},  // ℃
    {"celsius", Unit::Celsius},
    {"1", Unit::Count},
    {"-", Unit::Count},
    {"counts", Unit::Count},
}};

// Units split off a "q_u" name without the reader naming q (see split_column_name).
constexpr std::array<Spelling, 9> kUnitSuffixes{{
    {"mm", Unit::Millimetre},
    {"um", Unit::Micrometre},
    {"micron", Unit::Micrometre},
    {"nm", Unit::Nanometre},
    {"inch", Unit::Inch},
    {"urad", Unit::Microradian},
    {"mrad", Unit::Milliradian},
    {"arcsec", Unit::Arcsecond},
    {"deg", Unit::Degree},
}};

// `s` in lower case with every micro sign (µ U+00B5, μ U+03BC, or a Latin-1 byte 0xB5) as 'u',
// and a Latin-1 degree sign (0xB0) as UTF-8 '°'.
std::string unit_folded(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    const auto n = i + 1 < s.size() ? static_cast<unsigned char>(s[i + 1]) : 0;
    if ((c == 0xC2 && n == 0xB5) || (c == 0xCE && n == 0xBC)) {
      out += 'u';
      ++i;
    } else if (c >= 0xC2 && c <= 0xF4 && n >= 0x80) {  // another UTF-8 sequence: as it is
      out += s[i];
      for (; i + 1 < s.size() && (static_cast<unsigned char>(s[i + 1]) & 0xC0) == 0x80; ++i)
        out += s[i + 1];
    } else if (c == 0xB5) {  // a lone Latin-1 / Windows-1252 micro sign
      out += 'u';
    } else if (c == 0xB0) {  // a lone Latin-1 degree sign
      out += "\xC2\xB0";
    } else {
      out += static_cast<char>(c < 0x80 ? std::tolower(c) : c);
    }
  }
  return out;
}

// "q [u]", "q (u)", "q / u": the quantity and the unit text; nullopt for a name without one. A
// parenthesis that holds no unit ("probe A (front)") is part of the name: nullopt. Square
// brackets and " / " are only ever a unit, so what they hold is returned to be checked.
std::optional<std::pair<std::string_view, std::string_view>> unit_bracketed(std::string_view name) {
  const std::string_view n = detail::trim(name);
  if (n.size() >= 3 && (n.back() == ']' || n.back() == ')')) {
    const bool paren = n.back() == ')';
    const std::size_t at = n.rfind(paren ? '(' : '[');
    if (at != std::string_view::npos && at > 0) {
      const std::string_view inside = detail::trim(n.substr(at + 1, n.size() - at - 2));
      if (paren && !parse_unit(inside)) return std::nullopt;
      return std::pair{detail::trim(n.substr(0, at)), inside};
    }
  }
  if (const std::size_t slash = n.rfind(" / "); slash != std::string_view::npos && slash > 0)
    return std::pair{detail::trim(n.substr(0, slash)), detail::trim(n.substr(slash + 3))};
  return std::nullopt;
}

Unit checked_unit_of(std::string_view name, std::string_view text) {
  if (const std::optional<Unit> u = parse_unit(text)) return *u;
  throw Error(fmt::format(
      "column '{}': '{}' is not a unit this table can hold (lengths mm, µm, nm, m, in; angles "
      "rad, mrad, µrad, deg, arcsec; times s, ms, min; temperatures °C)",
      name, text));
}

}  // namespace

UnitKind kind_of(Unit u) {
  return info(u).kind;
}

std::string_view symbol(Unit u) {
  return info(u).symbol;
}

double unit_factor(Unit from, Unit to) {
  return from == to ? 1.0 : info(from).scale / info(to).scale;
}

std::optional<Unit> parse_unit(std::string_view symbol) {
  const std::string s = unit_folded(detail::trim(symbol));
  for (const Spelling& sp : kUnitSpellings)
    if (s == sp.text) return sp.unit;
  return std::nullopt;
}

std::string unit_refusal(std::string_view header, Unit written, std::string_view quantity,
                         Unit wanted) {
  if (kind_of(written) == kind_of(wanted)) return "";
  const auto kind = [](Unit u) {
    switch (kind_of(u)) {
      case UnitKind::Length:
        return "a length";
      case UnitKind::Angle:
        return "an angle";
      case UnitKind::Time:
        return "a time";
      case UnitKind::Temperature:
        return "a temperature";
      case UnitKind::Count:
        break;
    }
    return "a plain number";
  };
  return fmt::format("column '{}' is in {}, {}; {} holds {}{}", header, symbol(written),
                     kind(written), quantity, kind(wanted),
                     kind_of(wanted) == UnitKind::Count
                         ? " and takes no unit"
                         : fmt::format(" (for example in {})", symbol(wanted)));
}

ColumnName split_column_name(std::string_view name) {
  ColumnName out;
  if (const auto b = unit_bracketed(name); b && !b->first.empty()) {
    out.quantity = std::string(b->first);
    out.unit = checked_unit_of(name, b->second);
    out.unit_text = std::string(b->second);
    return out;
  }
  out.quantity = std::string(detail::trim(name));
  const std::size_t us = out.quantity.rfind('_');
  if (us != std::string::npos && us > 0) {
    const std::string tail = unit_folded(std::string_view(out.quantity).substr(us + 1));
    for (const Spelling& sp : kUnitSuffixes)
      if (tail == sp.text) {
        out.unit_text = out.quantity.substr(us + 1);
        out.unit = sp.unit;
        out.quantity.resize(us);
        return out;
      }
  }
  return out;
}

ColumnMatch column_matches(std::string_view header, std::string_view quantity) {
  const std::string q = unit_folded(quantity);
  const std::string_view h = detail::trim(header);
  if (unit_folded(h) == q) return {true, std::nullopt};
  if (const auto b = unit_bracketed(h); b && unit_folded(b->first) == q)
    return {true, checked_unit_of(header, b->second)};
  if (h.size() > quantity.size() + 1 && h[quantity.size()] == '_' &&
      unit_folded(h.substr(0, quantity.size())) == q)
    if (const std::optional<Unit> u = parse_unit(h.substr(quantity.size() + 1))) return {true, *u};
  return {};
}

}  // namespace trueaxis::io
