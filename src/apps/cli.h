#pragma once
// Shared by the command-line tools and the benchmarks: the one-line error with
// exit code 2 that bad input gets, strict number parsing for option values, and
// ArgParser, which walks argv the same way for every tool.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

namespace vitamin_e::cli {

[[noreturn]] inline void fail(const std::string& msg) {
  std::cerr << "error: " << msg << '\n';  // std::exit flushes
  std::exit(2);
}

// The whole of v as a number, else fail() naming the option.
inline double parseDouble(const std::string& key, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0') fail(key + " expects a number, got '" + v + "'");
  return d;
}

// The whole of v as an integer of type T (in its range), else fail() naming the option.
template <typename T>
T parseInteger(const std::string& key, const std::string& v) {
  static_assert(std::is_integral_v<T>, "an integer type");
  char* end = nullptr;
  errno = 0;
  const long long n = std::strtoll(v.c_str(), &end, 10);
  const bool in_range = errno == 0 && n >= static_cast<long long>(std::numeric_limits<T>::lowest()) &&
                        static_cast<unsigned long long>(std::max(n, 0LL)) <=
                            static_cast<unsigned long long>(std::numeric_limits<T>::max());
  if (v.empty() || *end != '\0' || !in_range) {
    fail(key + " expects " + (std::is_unsigned_v<T> ? "a non-negative integer" : "an integer") + ", got '" + v + "'");
  }
  return static_cast<T>(n);
}

// Options in any order: "-h"/"--help" prints the usage on stdout and exits 0; an
// unknown option, a missing or malformed value is one "error: ..." line on
// stderr and exit 2. Typical loop:
//   cli::ArgParser args(argc, argv, kUsage);
//   while (args.more()) {
//     if (args.flag("--quick", &quick) || args.value("--frames", &frames) || args.positional(&dir)) continue;
//     args.unknown();
//   }
class ArgParser {
 public:
  ArgParser(int argc, char** argv, std::string usage) : argc_(argc), argv_(argv), usage_(std::move(usage)) {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        std::cout << usage_;
        std::exit(0);
      }
    }
  }
  bool more() const { return i_ < argc_; }
  const std::string& usage() const { return usage_; }

  // The current argument is `name`: *on = true, consumed.
  bool flag(const char* name, bool* on) {
    if (current() != name) return false;
    *on = true;
    ++i_;
    return true;
  }
  // The current argument is `name`: the next one, parsed as T, goes to *out; both consumed.
  template <typename T>
  bool value(const char* name, T* out) {
    if (current() != name) return false;
    if (i_ + 1 >= argc_) fail(std::string(name) + " needs a value");
    const std::string v = argv_[i_ + 1];
    if constexpr (std::is_same_v<T, std::string>) {
      *out = v;
    } else if constexpr (std::is_same_v<T, bool>) {
      if (v == "1" || v == "true") *out = true;
      else if (v == "0" || v == "false") *out = false;
      else fail(std::string(name) + " expects 0 or 1, got '" + v + "'");
    } else if constexpr (std::is_integral_v<T>) {
      *out = parseInteger<T>(name, v);
    } else {
      const double d = parseDouble(name, v);
      if (!std::isfinite(d)) fail(std::string(name) + " expects a finite number, got '" + v + "'");
      *out = static_cast<T>(d);
    }
    i_ += 2;
    return true;
  }
  // The current argument is not an option: it goes to *out (once), consumed.
  bool positional(std::string* out) {
    const std::string& a = current();
    if (a.empty() || a[0] == '-' || !out->empty()) return false;
    *out = a;
    ++i_;
    return true;
  }
  [[noreturn]] void unknown() const {
    const std::string& a = current();
    fail(a.rfind('-', 0) == 0 ? "unknown option '" + a + "' (see --help)"
                              : "unexpected argument '" + a + "' (see --help)");
  }

 private:
  const std::string& current() const {
    static const std::string no_argument;
    if (i_ >= argc_) return no_argument;
    current_ = argv_[i_];
    return current_;
  }
  int argc_;
  char** argv_;
  std::string usage_;
  int i_ = 1;
  mutable std::string current_;
};

}  // namespace vitamin_e::cli
