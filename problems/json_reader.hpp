#pragma once
// Reading a scene file's JSON objects with field paths for error messages (problems/scene.cpp,
// problems/optimization.cpp). Internal to problems/.

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "../lib/state.hpp"
#include "scene.hpp"

namespace liedyn::scene_json {

using nlohmann::json;

// A JSON object being read, with the dotted path of its place in the file.
//
// Typos must not pass silently, and must be reported as typos: every reader is made with the
// keys its object may have, and the object's keys are checked against them at once, before
// any value is read. Checked only at the end, a misspelt key would hide behind the error its
// misspelling causes elsewhere in the object (a required key missing, a value read under
// another name), a message about the wrong field.
//
// Each key read is also remembered; finish() rejects the keys allowed but not read (a
// term's "height" is read with its "letter" only, not with its "targets").
class ObjectReader {
 public:
  using Keys = std::vector<std::string_view>;

  // Objects whose kind a member names ("type", "term", "kind") take other keys per kind.
  struct Variant {
    std::string_view value;  // of the naming member, e.g. "helix"
    Keys keys;               // allowed with it besides the common ones
  };
  struct Variants {
    std::string_view key;  // the naming member, e.g. "type"
    std::vector<Variant> variants;
  };

  // An object that may have `keys`.
  ObjectReader(const json& value, std::string path, const std::string& source, const Keys& keys)
      : ObjectReader(value, std::move(path), source, keys, Variants{}) {}

  // An object that may have `keys` and `variants.key`, and with it the keys of its variant.
  // An unknown kind (or none) allows the keys of every variant: the naming member's own
  // error comes from its reading, and only keys no kind takes are unknown here.
  ObjectReader(const json& value, std::string path, const std::string& source, const Keys& keys,
               const Variants& variants)
      : value_(value), path_(std::move(path)), source_(source) {
    if (!value_.is_object()) fail(path_, "must be a JSON object");
    for (const std::string_view k : keys) allowed_.emplace(k);
    if (!variants.key.empty()) {
      allowed_.emplace(variants.key);
      const auto named = value_.find(std::string(variants.key));
      const Variant* chosen = nullptr;
      for (const Variant& v : variants.variants) {
        if (named != value_.end() && named->is_string() && named->get<std::string>() == v.value) {
          chosen = &v;
          break;
        }
      }
      for (const Variant& v : variants.variants) {
        if (chosen != nullptr && chosen != &v) continue;
        for (const std::string_view k : v.keys) allowed_.emplace(k);
      }
    }
    check_keys();
  }

  // Every reader declares its keys (see above).
  ObjectReader(const json& value, std::string path, const std::string& source) = delete;

  [[noreturn]] void fail(const std::string& field, const std::string& reason) const {
    throw SceneError(source_, field, reason);
  }

  const std::string& source() const { return source_; }

  std::string field(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }

  bool has(const std::string& key) {
    // Every read passes here, present or not: a key read but not declared is a bug of the
    // reading code (a valid scene giving it would be refused), whatever the scene holds.
    if (!allowed_.count(key)) {
      throw std::logic_error("scene reader: " + field(key) + " is read but not declared");
    }
    known_.insert(key);
    return value_.contains(key);
  }

  const json& get(const std::string& key) {
    if (!has(key)) fail(field(key), "is required but missing");
    return value_.at(key);
  }

  double number(const std::string& key) { return to_number(get(key), field(key)); }
  double number(const std::string& key, double fallback) {
    return has(key) ? number(key) : fallback;
  }

  double to_number(const json& v, const std::string& f) const {
    if (!v.is_number()) fail(f, "must be a number (got " + type_of(v) + ")");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(f, "must be finite");
    return x;
  }

  int integer(const std::string& key, int lo, int hi = std::numeric_limits<int>::max()) {
    return to_integer(get(key), field(key), lo, hi);
  }

  int to_integer(const json& v, const std::string& f, int lo,
                 int hi = std::numeric_limits<int>::max()) const {
    if (!v.is_number_integer()) {
      fail(f, "must be an integer (got " + (v.is_number() ? v.dump() : type_of(v)) + ")");
    }
    const std::string range = "must be an integer in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "] (got " + v.dump() + ")";
    // Unsigned values above the range of long long would wrap in get<long long>().
    if (v.is_number_unsigned() &&
        v.get<unsigned long long>() > static_cast<unsigned long long>(hi)) {
      fail(f, range);
    }
    const auto x = v.get<long long>();
    if (x < lo || x > hi) fail(f, range);
    return static_cast<int>(x);
  }

  std::string string(const std::string& key) {
    const json& v = get(key);
    if (!v.is_string()) fail(field(key), "must be a string (got " + type_of(v) + ")");
    return v.get<std::string>();
  }
  std::string string(const std::string& key, const std::string& fallback) {
    return has(key) ? string(key) : fallback;
  }
  bool boolean(const std::string& key, bool fallback) {
    if (!has(key)) return fallback;
    const json& v = value_.at(key);
    if (!v.is_boolean()) fail(field(key), "must be true or false (got " + type_of(v) + ")");
    return v.get<bool>();
  }

  // Fixed-length array of finite numbers.
  template <int N>
  Eigen::Matrix<double, N, 1> vector(const std::string& key) {
    return to_vector<N>(get(key), field(key));
  }
  template <int N>
  Eigen::Matrix<double, N, 1> to_vector(const json& v, const std::string& f) const {
    if (!v.is_array() || v.size() != N) {
      fail(f, "must be an array of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out(i) = to_number(v[i], f + "[" + std::to_string(i) + "]");
    return out;
  }
  template <int N>
  Eigen::Matrix<double, N, 1> vector(const std::string& key,
                                     const Eigen::Matrix<double, N, 1>& fallback) {
    return has(key) ? vector<N>(key) : fallback;
  }

  // An inertia tensor: 3 principal moments or a 3×3 array.
  Matrix3 inertia(const std::string& key) {
    const json& v = get(key);
    const std::string f = field(key);
    if (v.is_array() && v.size() == 3 && v[0].is_number()) return vector<3>(key).asDiagonal();
    if (v.is_array() && v.size() == 3) {
      Matrix3 m;
      for (int r = 0; r < 3; ++r) {
        const std::string row = f + "[" + std::to_string(r) + "]";
        if (!v[r].is_array() || v[r].size() != 3) fail(row, "must be an array of 3 numbers");
        for (int c = 0; c < 3; ++c) m(r, c) = to_number(v[r][c], row + "[" + std::to_string(c) + "]");
      }
      return m;
    }
    fail(f, "must be 3 principal moments [I1, I2, I3] or a 3×3 array");
  }

  const json& array(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array()) fail(field(key), "must be an array (got " + type_of(v) + ")");
    return v;
  }

  void finish() const { reject_keys_outside(known_); }

  static std::string type_of(const json& v) {
    return v.is_null() ? "null" : std::string(v.type_name());
  }

 private:
  void check_keys() const { reject_keys_outside(allowed_); }

  // Fails on the first key of the object (in its order) not in `keys`, listing them.
  template <class Set>
  void reject_keys_outside(const Set& keys) const {
    for (const auto& item : value_.items()) {
      if (!keys.count(item.key())) {
        std::string allowed;
        for (const std::string& k : keys) allowed += (allowed.empty() ? "" : ", ") + k;
        fail(field(item.key()), "unknown key (allowed here: " + allowed + ")");
      }
    }
  }

  const json& value_;
  std::string path_;
  const std::string& source_;
  std::set<std::string, std::less<>> allowed_;  // declared: checked when made
  std::set<std::string> known_;                 // read: checked by finish()
};

inline std::string item_path(const std::string& array, std::size_t i) {
  return array + "[" + std::to_string(i) + "]";
}

}  // namespace liedyn::scene_json
