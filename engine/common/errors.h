#pragma once
/// Error kinds of the engine (see ../shared/docs/STYLE.md, "Errors"):
///  1. InputError: bad input from a person. Names the file, the key, the value and what was expected.
///     The CLI prints what() as one line and exits with code 2.
///  2. Numerical outcomes are data (a status and a message in each run's result), never exceptions.
///  3. Broken internal invariants: GESWEEP_DEMAND aborts with a message.

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace gesweep {

/// Bad input from a person: a study file, an aircraft file or a command-line flag.
class InputError : public std::runtime_error {
 public:
  /// @param source  the file path, or "command line"
  /// @param key     the key or flag at fault (may be empty when the whole file is at fault)
  /// @param value   the offending value as the person wrote it (may be empty)
  /// @param expected what was expected instead
  /// @param line    1-based line in the file where known, else 0
  InputError(std::string source, std::string key, std::string value, std::string expected, int line = 0);

  const std::string& source() const { return source_; }
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& expected() const { return expected_; }
  int line() const { return line_; }

 private:
  std::string source_, key_, value_, expected_;
  int line_ = 0;
};

/// A number as a person would write it in a message: shortest form up to 10 significant digits.
std::string ShortNumber(double value);

/// Aborts with file, line and message when an internal invariant is broken (Drake's DEMAND).
#define GESWEEP_DEMAND(condition)                                                              \
  do {                                                                                         \
    if (!(condition)) {                                                                        \
      std::fprintf(stderr, "gesweep: internal error at %s:%d: failed %s\n", __FILE__, __LINE__, \
                   #condition);                                                                \
      std::abort();                                                                            \
    }                                                                                          \
  } while (false)

}  // namespace gesweep
