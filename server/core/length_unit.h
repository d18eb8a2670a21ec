// Units of length: what a volume's spacing is measured in (docs/scenes.md, "Units"). Files name
// them in many spellings (NGFF's "micrometer", NRRD's "mm", ImageJ's "micron"); peakcast keeps the
// SI symbol ("µm") and shows it wherever a length is shown. An empty unit means the file said
// nothing: lengths are then shown in "units".
#pragma once

#include <array>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

namespace peakcast {

struct LengthUnit {
  const char* symbol;  // "nm", "µm", "mm", ...: what is shown
  double metres;       // one unit in metres
};

// The word shown for lengths of a volume whose file names no unit.
inline constexpr const char* kNoUnit = "units";

// A unit's name in any common spelling (NGFF/UDUNITS names, SI symbols, "um", "micron", British
// "-metre", plurals; case-sensitive only where SI is: "mm" against "Mm"). nullopt when it is
// not a length.
std::optional<LengthUnit> parse_length_unit(const std::string& name);
// Words that say "no unit" ("", "pixel", "voxel", "unknown", "none", "units"): true.
bool says_no_unit(const std::string& name);
// The symbol for `name`: "" for a word that says no unit; std::invalid_argument naming `key`
// and the accepted units when it is neither (a time, a mass, a typo).
std::string length_symbol(const std::string& name, const std::string& key);
// One unit per axis (a file may give z in µm and x, y in nm): the finest of them, with spacing
// and origin converted into it. Axes that say no unit take the others' unit. "" when none has one.
// std::invalid_argument naming `key` when one is not a length.
std::string common_unit(const std::array<std::string, 3>& names, glm::dvec3& spacing, glm::dvec3& origin,
                        const std::string& key);

// NGFF's name of a symbol common_unit returns ("µm": "micrometer"); "" for "" (no unit).
std::string ngff_unit_name(const std::string& symbol);

}  // namespace peakcast
