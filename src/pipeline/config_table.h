#pragma once
// Internal to the pipeline module: the table of configuration fields
// (config_table.cpp) that system_config.cpp loads, validates, prints and
// documents from. One row per yaml key; members without a key are rows too,
// marked internal, so that the table covers every member of every config struct.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline::detail {

struct Field {
  std::string section;
  std::string key;
  std::string doc;
  std::string internal;                         // non-empty: not a yaml key
  std::vector<const void*> members;             // what the row sets; the first is printed
  std::function<void(const YAML::Node&)> read;  // empty for internal rows
  std::function<std::string()> print;
};

// The shortest text that reads back as the same double (whole numbers without an exponent).
inline std::string formatDouble(double v) {
  char buf[40];
  if (std::floor(v) == v && std::abs(v) < 1e15) {
    std::snprintf(buf, sizeof(buf), "%.0f", v);
    return buf;
  }
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

template <typename T>
std::string formatValue(const T& v) {
  if constexpr (std::is_same_v<T, bool>) {
    return v ? "true" : "false";
  } else if constexpr (std::is_integral_v<T>) {
    return std::to_string(v);
  } else {
    return formatDouble(static_cast<double>(v));
  }
}

// Throws std::runtime_error saying what is wrong with the value.
template <typename T>
T parseValue(const YAML::Node& node) {
  if (!node.IsScalar()) throw std::runtime_error("not a single value");
  if constexpr (std::is_same_v<T, bool>) {
    return node.as<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    const double d = node.as<double>();
    if (!std::isfinite(d) || std::floor(d) != d) throw std::runtime_error("not an integer");
    if (std::is_unsigned_v<T> && d < 0) throw std::runtime_error("must not be negative");
    if (d < static_cast<double>(std::numeric_limits<T>::lowest()) ||
        d >= std::ldexp(1.0, std::numeric_limits<T>::digits)) {
      throw std::runtime_error("out of range");
    }
    return static_cast<T>(d);
  } else {
    const double d = node.as<double>();
    if (!std::isfinite(d)) throw std::runtime_error("not finite");
    return static_cast<T>(d);
  }
}

class Table {
 public:
  void section(const std::string& name) { section_ = name; }

  // A yaml key for one member.
  template <typename T>
  void key(const std::string& key, T* value, const std::string& doc) {
    shared(key, std::vector<T*>{value}, doc);
  }
  // A yaml key that sets several members to the same value (one meaning, several users).
  template <typename T>
  void shared(const std::string& key, const std::vector<T*>& values, const std::string& doc) {
    Field f = make(key, doc, values);
    const std::string name = section_ + "." + key;
    f.read = [values, name](const YAML::Node& node) {
      T v;
      try {
        v = parseValue<T>(node);
      } catch (const std::exception& e) {
        throw ConfigError(name + ": bad value '" + YAML::Dump(node) + "' (" + e.what() + ")");
      }
      for (T* p : values) *p = v;
    };
    T* first = values.front();
    f.print = [first] { return formatValue(*first); };
    fields.push_back(std::move(f));
  }
  // A yaml key naming one of the values of an enum.
  template <typename E>
  void choice(const std::string& key, E* value, const std::vector<std::pair<std::string, E>>& names,
              const std::string& doc) {
    Field f = make(key, doc, std::vector<E*>{value});
    const std::string name = section_ + "." + key;
    f.read = [value, names, name](const YAML::Node& node) {
      std::string text, all;
      try {
        text = node.IsScalar() ? node.Scalar() : YAML::Dump(node);
      } catch (const std::exception&) {
        text.clear();  // not printable: matches no name, the error below lists the names
      }
      for (const auto& [n, v] : names) {
        if (n == text) {
          *value = v;
          return;
        }
        all += (all.empty() ? "" : ", ") + n;
      }
      throw ConfigError(name + ": bad value '" + text + "' (one of: " + all + ")");
    };
    f.print = [value, names] {
      for (const auto& [n, v] : names) {
        if (v == *value) return n;
      }
      return std::string("?");
    };
    fields.push_back(std::move(f));
  }
  // A member that is not settable: the system sets it (how says from what).
  template <typename T>
  void internal(const std::string& key, T* value, const std::string& how) {
    Field f = make(key, "", std::vector<T*>{value});
    f.internal = how;
    f.print = [value] { return formatValue(*value); };
    fields.push_back(std::move(f));
  }

  std::vector<Field> fields;

 private:
  template <typename T>
  Field make(const std::string& key, const std::string& doc, const std::vector<T*>& values) {
    Field f;
    f.section = section_;
    f.key = key;
    f.doc = doc;
    for (T* p : values) f.members.push_back(p);
    return f;
  }
  std::string section_;
};

struct SectionInfo {
  const char* name;
  const char* about;  // one paragraph of docs/CONFIG.md
};

// The rows, pointing into c (loading writes through them).
std::vector<Field> configTable(SystemConfig& c);
// The sections in the order of the table.
const std::vector<SectionInfo>& configSections();

}  // namespace vitamin_e::pipeline::detail
