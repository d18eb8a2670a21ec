// Reading JSON fields with messages that name the key ("render.s_k: must be > 0"): shared
// by the scene and the ray-texture parsers. Every failure throws SceneError.
#pragma once

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <utility>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "core/scene_error.h"

namespace peakcast::json_fields {

using json = nlohmann::json;

[[noreturn]] inline void fail(const std::string& key, const std::string& what) { throw SceneError(key + ": " + what); }

inline void only_keys(const json& j, const std::string& where, std::initializer_list<const char*> allowed) {
  if (!j.is_object()) fail(where.empty() ? "scene" : where, "must be an object");
  for (auto& item : j.items()) {
    const std::string& k = item.key();
    bool ok = std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return k == a; });
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      fail(where.empty() ? k : where + "." + k, "unknown key (allowed: " + list + ")");
    }
  }
}

inline double number(const json& j, const std::string& key) {
  if (!j.is_number()) fail(key, "must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(key, "must be finite");
  return v;
}

inline int integer(const json& j, const std::string& key, int lo, int hi) {
  if (!j.is_number_integer() && !(j.is_number() && std::floor(j.get<double>()) == j.get<double>()))
    fail(key, "must be an integer");
  const double v = j.get<double>();
  if (v < lo || v > hi) fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(v);
}

inline bool boolean(const json& j, const std::string& key) {
  if (!j.is_boolean()) fail(key, "must be true or false");
  return j.get<bool>();
}

inline glm::dvec3 vec3(const json& j, const std::string& key) {
  if (!j.is_array() || j.size() != 3) fail(key, "must be an array of 3 numbers");
  return {number(j[0], key + "[0]"), number(j[1], key + "[1]"), number(j[2], key + "[2]")};
}

template <typename E>
E choice(const json& j, const std::string& key, std::initializer_list<std::pair<const char*, E>> options) {
  if (!j.is_string()) fail(key, "must be a string");
  std::string list;
  for (auto& [name, value] : options) {
    if (j.get<std::string>() == name) return value;
    list += std::string(list.empty() ? "" : ", ") + name;
  }
  std::string what = "'";  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "x" + string&&
  what += j.get<std::string>();
  what += "' is not one of ";
  what += list;
  fail(key, what);
}

}  // namespace peakcast::json_fields
