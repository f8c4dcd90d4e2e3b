#include "core/json_reader.h"

#include <fmt/format.h>

#include <cmath>

#include "nimbus/error.h"

namespace nimbus {

namespace {

std::string type_name(const nlohmann::json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_array()) return "an array";
  if (v.is_object()) return "an object";
  if (v.is_boolean()) return "a boolean";
  return "null";
}

std::string fmt_bound(double x) { return fmt::format("{:g}", x); }

}  // namespace

JsonObject::JsonObject(const nlohmann::json& j, std::string where, std::string path)
    : j_(j), where_(std::move(where)), path_(std::move(path)) {
  if (!j_.is_object()) fail_here(fmt::format("must be an object, not {}", type_name(j_)));
}

void JsonObject::fail(const std::string& key, const std::string& message) const {
  throw Error(fmt::format("{}: {}: {}", where_, path_of(key), message));
}

void JsonObject::fail_here(const std::string& message) const {
  throw Error(fmt::format("{}: {}: {}", where_, path_.empty() ? "/" : path_, message));
}

const nlohmann::json& JsonObject::field(const std::string& key) {
  used_.insert(key);
  const auto it = j_.find(key);
  if (it == j_.end()) fail(key, "required field is missing");
  return *it;
}

const nlohmann::json& JsonObject::raw(const std::string& key) { return field(key); }

double JsonObject::check_number(const nlohmann::json& v, const std::string& path) const {
  if (!v.is_number())
    throw Error(fmt::format("{}: {}: must be a number, not {}", where_, path, type_name(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw Error(fmt::format("{}: {}: must be finite", where_, path));
  return x;
}

double JsonObject::number(const std::string& key, double lo, double hi) {
  const double x = check_number(field(key), path_of(key));
  if (x < lo) fail(key, fmt::format("must be >= {}", fmt_bound(lo)));
  if (x > hi) fail(key, fmt::format("must be <= {}", fmt_bound(hi)));
  return x;
}

double JsonObject::number(const std::string& key, double lo, double hi, double fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return number(key, lo, hi);
}

double JsonObject::number_open_below(const std::string& key, double lo, double hi) {
  const double x = check_number(field(key), path_of(key));
  if (!(x > lo)) fail(key, fmt::format("must be > {}", fmt_bound(lo)));
  if (x > hi) fail(key, fmt::format("must be <= {}", fmt_bound(hi)));
  return x;
}

double JsonObject::number_open_below(const std::string& key, double lo, double hi, double fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return number_open_below(key, lo, hi);
}

int64_t JsonObject::integer(const std::string& key, int64_t lo, int64_t hi) {
  const nlohmann::json& v = field(key);
  const double x = check_number(v, path_of(key));
  if (std::floor(x) != x) fail(key, "must be a whole number");
  if (x < double(lo)) fail(key, fmt::format("must be >= {}", lo));
  if (x > double(hi)) fail(key, fmt::format("must be <= {}", hi));
  return v.is_number_integer() ? v.get<int64_t>() : int64_t(x);
}

int64_t JsonObject::integer(const std::string& key, int64_t lo, int64_t hi, int64_t fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return integer(key, lo, hi);
}

std::string JsonObject::string(const std::string& key) {
  const nlohmann::json& v = field(key);
  if (!v.is_string()) fail(key, fmt::format("must be a string, not {}", type_name(v)));
  return v.get<std::string>();
}

bool JsonObject::boolean(const std::string& key, bool fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  const nlohmann::json& v = field(key);
  if (!v.is_boolean()) fail(key, fmt::format("must be true or false, not {}", type_name(v)));
  return v.get<bool>();
}

std::string JsonObject::string(const std::string& key, const std::string& fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return string(key);
}

Vec3 JsonObject::vec3(const std::string& key) {
  const nlohmann::json& v = field(key);
  if (!v.is_array() || v.size() != 3) fail(key, "must be an array of 3 numbers");
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = check_number(v[i], fmt::format("{}/{}", path_of(key), i));
  return r;
}

Vec3 JsonObject::vec3(const std::string& key, const Vec3& fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return vec3(key);
}

Rgb JsonObject::rgb(const std::string& key, double lo) {
  const nlohmann::json& v = field(key);
  Rgb r;
  if (v.is_number()) {
    const double x = check_number(v, path_of(key));
    r = Rgb(x, x, x);
  } else if (v.is_array() && v.size() == 3) {
    for (int i = 0; i < 3; ++i) r[i] = check_number(v[i], fmt::format("{}/{}", path_of(key), i));
  } else {
    fail(key, "must be a number or an array [r, g, b]");
  }
  for (int i = 0; i < 3; ++i) {
    if (r[i] < lo) {
      const std::string p = v.is_array() ? fmt::format("{}/{}", path_of(key), i) : path_of(key);
      throw Error(fmt::format("{}: {}: must be >= {}", where_, p, fmt_bound(lo)));
    }
  }
  return r;
}

Rgb JsonObject::rgb(const std::string& key, double lo, const Rgb& fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return rgb(key, lo);
}

JsonObject JsonObject::object(const std::string& key) { return JsonObject(field(key), where_, path_of(key)); }

std::vector<JsonObject> JsonObject::array_of_objects(const std::string& key, bool allow_empty) {
  const nlohmann::json& v = field(key);
  if (!v.is_array()) fail(key, fmt::format("must be an array, not {}", type_name(v)));
  if (v.empty() && !allow_empty) fail(key, "must not be empty");
  std::vector<JsonObject> out;
  for (size_t i = 0; i < v.size(); ++i) out.emplace_back(v[i], where_, fmt::format("{}/{}", path_of(key), i));
  return out;
}

void JsonObject::finish() const {
  for (auto it = j_.begin(); it != j_.end(); ++it) {
    if (!used_.count(it.key())) {
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      fail(it.key(), fmt::format("unknown field (known here: {})", known));
    }
  }
}

int JsonObject::choice(const std::string& key, const std::vector<std::string>& names, int fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  const std::string v = string(key);
  for (size_t i = 0; i < names.size(); ++i)
    if (v == names[i]) return int(i);
  std::string list;
  for (size_t i = 0; i < names.size(); ++i)
    list += (i == 0 ? "" : (names.size() == 2 ? " or " : ", ")) + ("\"" + names[i] + "\"");
  fail(key, names.size() == 2 ? "must be " + list : "must be one of " + list);
}

std::optional<int64_t> JsonObject::optional_integer(const std::string& key, int64_t lo, int64_t hi) {
  if (!has(key)) {
    used_.insert(key);  // a known field: listed in the unknown-field message
    return std::nullopt;
  }
  return integer(key, lo, hi);
}

bool JsonObject::keyword_or_number(const std::string& key, const std::string& keyword, double lo, double hi,
                                   double* value) {
  if (!has(key)) {
    used_.insert(key);
    return false;
  }
  if (raw(key).is_string()) {
    if (string(key) != keyword)
      fail(key, fmt::format("must be \"{}\" or a number in [{}, {}]", keyword, fmt_bound(lo), fmt_bound(hi)));
    return false;
  }
  *value = number(key, lo, hi);
  return true;
}

bool JsonObject::keyword_or_integer(const std::string& key, const std::string& keyword, int64_t lo,
                                    int64_t hi, int64_t* value) {
  if (!has(key)) {
    used_.insert(key);
    return false;
  }
  if (raw(key).is_string()) {
    if (string(key) != keyword)
      fail(key, fmt::format("must be \"{}\" or an integer in [{}, {}]", keyword, lo, hi));
    return false;
  }
  *value = integer(key, lo, hi);
  return true;
}

bool JsonObject::keyword_or_boolean(const std::string& key, const std::string& keyword, bool* value) {
  if (!has(key)) {
    used_.insert(key);
    return false;
  }
  const nlohmann::json& v = field(key);
  if (v.is_string() && v.get<std::string>() == keyword) return false;
  if (!v.is_boolean())
    fail(key, fmt::format("must be \"{}\", true or false, not {}", keyword,
                          v.is_string() ? "\"" + v.get<std::string>() + "\"" : type_name(v)));
  *value = v.get<bool>();
  return true;
}

}  // namespace nimbus
