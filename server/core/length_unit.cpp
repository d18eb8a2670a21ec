#include "core/length_unit.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <vector>

namespace peakcast {
namespace {

struct Spelling {
  const char* prefix_word;  // "micro": "micrometer", "micrometre", "micrometers", ...
  const char* symbol;       // "µm"
  double metres;
};

// NGFF 0.4's space units (UDUNITS-2 names), in order of size.
constexpr Spelling kSi[] = {
    {"yocto", "ym", 1e-24}, {"zepto", "zm", 1e-21}, {"atto", "am", 1e-18}, {"femto", "fm", 1e-15},
    {"pico", "pm", 1e-12},  {"nano", "nm", 1e-9},   {"micro", "µm", 1e-6}, {"milli", "mm", 1e-3},
    {"centi", "cm", 1e-2},  {"deci", "dm", 1e-1},   {"", "m", 1.0},        {"hecto", "hm", 1e2},
    {"kilo", "km", 1e3},    {"mega", "Mm", 1e6},    {"giga", "Gm", 1e9},   {"tera", "Tm", 1e12},
    {"peta", "Pm", 1e15},   {"exa", "Em", 1e18},    {"zetta", "Zm", 1e21}, {"yotta", "Ym", 1e24},
};

struct Other {
  std::vector<const char*> words;  // lower case
  LengthUnit unit;
};
const std::vector<Other>& others() {
  static const std::vector<Other> o = {
      {{"angstrom", "angstroms", "ångström", "ångströms", "å", "\xe2\x84\xab"}, {"Å", 1e-10}},
      {{"um", "µm", "\xce\xbcm", "micron", "microns"}, {"µm", 1e-6}},  // µ: micro sign; μ: Greek mu
      {{"inch", "inches", "in"}, {"in", 0.0254}},
      {{"foot", "feet", "ft"}, {"ft", 0.3048}},
      {{"yard", "yards", "yd"}, {"yd", 0.9144}},
      {{"mile", "miles", "mi"}, {"mi", 1609.344}},
      {{"parsec", "parsecs", "pc"}, {"pc", 3.0856775814913673e16}},
  };
  return o;
}

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n\"");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n\"") - b + 1);
}

}  // namespace

bool says_no_unit(const std::string& name) {
  const std::string n = lower(trimmed(name));
  return n.empty() || n == "pixel" || n == "pixels" || n == "px" || n == "voxel" || n == "voxels" || n == "unknown" ||
         n == "none" || n == "unit" || n == kNoUnit || n == "???";
}

std::optional<LengthUnit> parse_length_unit(const std::string& raw) {
  const std::string name = trimmed(raw);
  for (const auto& s : kSi)  // symbols are case-sensitive: "mm" is not "Mm"
    if (name == s.symbol) return LengthUnit{s.symbol, s.metres};
  const std::string n = lower(name);
  for (const auto& o : others())
    for (const char* w : o.words)
      if (n == w) return o.unit;
  for (const auto& s : kSi) {
    const std::string p = s.prefix_word;
    for (const char* end : {"meter", "meters", "metre", "metres"})
      if (n == p + end) return LengthUnit{s.symbol, s.metres};
  }
  return std::nullopt;
}

std::string length_symbol(const std::string& name, const std::string& key) {
  if (says_no_unit(name)) return "";
  if (auto u = parse_length_unit(name)) return u->symbol;
  std::string shown = trimmed(name).substr(0, 40);
  throw std::invalid_argument(key + ": '" + shown +
                              "' is not a unit of length (nm, µm, mm, cm, m, Å, or their names: nanometer, "
                              "micrometer, millimeter, ...)");
}

std::string common_unit(const std::array<std::string, 3>& names, glm::dvec3& spacing, glm::dvec3& origin,
                        const std::string& key) {
  std::array<std::optional<LengthUnit>, 3> units;
  std::optional<LengthUnit> finest;
  for (int a = 0; a < 3; ++a) {
    if (length_symbol(names[size_t(a)], key).empty()) continue;
    units[size_t(a)] = parse_length_unit(names[size_t(a)]);
    if (!finest || units[size_t(a)]->metres < finest->metres) finest = units[size_t(a)];
  }
  if (!finest) return "";
  for (int a = 0; a < 3; ++a) {
    if (!units[size_t(a)]) continue;  // no unit: taken to be the others'
    const double f = units[size_t(a)]->metres / finest->metres;
    spacing[a] *= f;
    origin[a] *= f;
  }
  return finest->symbol;
}

std::string ngff_unit_name(const std::string& symbol) {
  for (const auto& s : kSi)
    if (symbol == s.symbol) return std::string(s.prefix_word) + "meter";
  static const std::pair<const char*, const char*> named[] = {{"Å", "angstrom"}, {"in", "inch"}, {"ft", "foot"},
                                                              {"yd", "yard"},    {"mi", "mile"}, {"pc", "parsec"}};
  for (const auto& [sym, name] : named)
    if (symbol == sym) return name;
  return "";
}

}  // namespace peakcast
