#pragma once
// Shared by the command-line tools: the one-line error with exit code 2 that
// bad input gets, and strict number parsing for option values.
#include <cstdlib>
#include <iostream>
#include <string>

namespace vitamin_e::cli {

[[noreturn]] inline void fail(const std::string& msg) {
  std::cerr << "error: " << msg << std::endl;
  std::exit(2);
}

// The whole of v as a number, else fail() naming the option.
inline double parseDouble(const std::string& key, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0') fail(key + " expects a number, got '" + v + "'");
  return d;
}

}  // namespace vitamin_e::cli
