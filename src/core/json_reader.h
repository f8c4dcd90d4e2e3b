// Strict reading of JSON objects: every field checked for type and range, unknown keys rejected,
// every error a nimbus::Error "FILE: /json/pointer: message".
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/math.h"

namespace nimbus {

class JsonObject {
 public:
  // `where` names the document in messages (usually the file name); `path` is the JSON pointer.
  JsonObject(const nlohmann::json& j, std::string where, std::string path);

  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  [[noreturn]] void fail_here(const std::string& message) const;
  std::string path_of(const std::string& key) const { return path_ + "/" + key; }
  const std::string& where() const { return where_; }
  const std::string& path() const { return path_; }

  bool has(const std::string& key) const { return j_.contains(key); }
  // has(key), and the key counts as known either way (listed in unknown-field messages).
  bool present(const std::string& key) {
    used_.insert(key);
    return has(key);
  }
  const nlohmann::json& raw(const std::string& key);  // marks the key used; must exist

  // Numbers: finite, within [lo, hi] (inclusive unless the *_open variants).
  double number(const std::string& key, double lo, double hi);
  double number(const std::string& key, double lo, double hi, double fallback);
  double number_open_below(const std::string& key, double lo, double hi);  // lo < x <= hi
  double number_open_below(const std::string& key, double lo, double hi, double fallback);
  int64_t integer(const std::string& key, int64_t lo, int64_t hi);
  int64_t integer(const std::string& key, int64_t lo, int64_t hi, int64_t fallback);
  std::optional<int64_t> optional_integer(const std::string& key, int64_t lo, int64_t hi);  // nullopt: absent
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  bool boolean(const std::string& key, bool fallback);
  // One of `names` (a string); returns its index, `fallback` when the key is absent.
  // Message: must be "a" or "b" (or: must be one of "a", "b", "c").
  int choice(const std::string& key, const std::vector<std::string>& names, int fallback);
  // Either the string `keyword` (returns false: the caller keeps its "auto"-like default) or a number in
  // [lo, hi] written to *value (returns true). Message: must be "keyword" or a number in [lo, hi].
  bool keyword_or_number(const std::string& key, const std::string& keyword, double lo, double hi,
                         double* value);
  bool keyword_or_integer(const std::string& key, const std::string& keyword, int64_t lo, int64_t hi,
                          int64_t* value);
  // Either the string `keyword` (returns false) or true / false written to *value (returns true).
  bool keyword_or_boolean(const std::string& key, const std::string& keyword, bool* value);
  Vec3 vec3(const std::string& key);
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  // A number (grey) or [r, g, b], each component >= lo.
  Rgb rgb(const std::string& key, double lo);
  Rgb rgb(const std::string& key, double lo, const Rgb& fallback);
  JsonObject object(const std::string& key);
  std::vector<JsonObject> array_of_objects(const std::string& key, bool allow_empty);

  // Throws if any key was not read: a typo must not silently render something else.
  void finish() const;

 private:
  const nlohmann::json& field(const std::string& key);
  double check_number(const nlohmann::json& v, const std::string& path) const;

  const nlohmann::json& j_;
  std::string where_, path_;
  std::set<std::string> used_;
};

}  // namespace nimbus
