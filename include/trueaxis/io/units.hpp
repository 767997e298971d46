// trueaxis::io — units written in a table's column names.
//
// Instruments and spreadsheets name their columns with the unit: "x [mm]", "deviation (µm)",
// "height / nm" (the quantity/unit form of ISO 80000-1, clause 7.1), "target_mm", "deviation_um".
// A reader asks for a column by its quantity ("deviation") in the unit it computes in (µm); a
// column named with a unit of the same kind is converted, one of another kind ("deviation [s]")
// is refused, and one named without a unit is taken to be in the reader's unit, as before.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace trueaxis::io {

// What a column measures; units convert only within one kind.
enum class UnitKind { Length, Angle, Time, Temperature, Count };

// The units a column name may carry. Count is a plain number (a cycle, a current in counts): a
// column of counts may carry no unit.
enum class Unit {
  Metre,
  Millimetre,
  Micrometre,
  Nanometre,
  Inch,
  Radian,
  Milliradian,
  Microradian,
  Degree,
  Arcsecond,
  Second,
  Millisecond,
  Minute,
  Celsius,
  Count,
};

UnitKind kind_of(Unit u);
// The symbol a message shows: "mm", "µm", "µrad", "°C", ….
std::string_view symbol(Unit u);
// The factor from `from` to `to` (same kind): a value in `from` times it is the value in `to`.
// Precondition: kind_of(from) == kind_of(to).
double unit_factor(Unit from, Unit to);

// The unit a symbol names ("mm", "um", "µm", "μm", "micron", "nm", "m", "in", "inch", "rad",
// "mrad", "urad", "µrad", "deg", "°", "arcsec", "\"", "s", "ms", "min", "C", "°C", "degC"), case
// aside; nullopt for anything else.
std::optional<Unit> parse_unit(std::string_view symbol);

// A column name split into its quantity and its unit.
struct ColumnName {
  std::string quantity;      // "deviation"
  std::optional<Unit> unit;  // µm; nullopt when the name carries none
  std::string unit_text;     // the unit as written ("µm"), for messages
};

// Splits a column name written "q [u]", "q[u]", "q (u)", "q / u" or "q_u". Square brackets or a
// slash holding no unit ("x [furlong]") throw Error naming it; a parenthesis holding no unit is
// part of the name ("probe A (front)"). The "q_u" form is split only for
// units no one uses as a name's last word (mm, um, µm, nm, urad, µrad, mrad, arcsec, deg, inch):
// a probe called "probe_c" or a detector "laser_in" keeps its name. A name the reader already
// knows, "material_temp_c" or "time_s", is matched by column_matches below with any symbol.
ColumnName split_column_name(std::string_view name);

// Why the column `header`, written in `written`, cannot hold `quantity` read in `wanted`: a unit
// of another kind ("column 't [s]' is in s, a time; t holds a length (for example in mm)"), or
// any unit on a plain number. Empty when it can.
std::string unit_refusal(std::string_view header, Unit written, std::string_view quantity,
                         Unit wanted);

// Whether the column called `header` holds `quantity`, and in what unit. It does when `header` is
// `quantity` itself (no unit written), `quantity` with a bracketed or slashed unit, or `quantity`
// + "_" + a symbol; case aside.
struct ColumnMatch {
  bool holds = false;
  std::optional<Unit> unit;  // nullopt: no unit written
};
ColumnMatch column_matches(std::string_view header, std::string_view quantity);

}  // namespace trueaxis::io
