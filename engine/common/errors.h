#pragma once
/// Error kinds of the engine (docs/architecture.md, "Rules that hold throughout"):
///  1. InputError: bad input from a person. Names the file, the key, the value and what was expected.
///     The CLI prints what() as one line and exits with code 2.
///  2. Numerical outcomes are data (a status and a message in each run's result), never exceptions.
///  3. Broken internal invariants: GESWEEP_DEMAND aborts with a message.

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

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

/// A number as a person would write it in a message: shortest form up to 10 significant digits,
/// scientific where that is shorter ("1e-10", never "0.000000"); "nan", "inf", "-inf". The one number
/// formatter of every message (InputError values, run messages, CLI refusals).
std::string ShortNumber(double value);

/// `text` made safe to print on a terminal as part of one line: valid UTF-8 passes unchanged; line
/// breaks and tabs become "\n", "\r", "\t"; every other control character (C0, DEL and the C1
/// controls U+0080-U+009F, which include the 8-bit CSI) becomes "\xNN" or "\u00NN"; every byte
/// that is not part of a valid UTF-8 sequence becomes "\xNN". The result is printable and never
/// holds a byte that could start an escape sequence or split a character. Applying it twice
/// changes nothing more than applying it once (the output is printable).
std::string EscapeForMessage(std::string_view text);

/// Aborts with file, line and message when an internal invariant is broken (Drake's DEMAND).
#define GESWEEP_DEMAND(condition)                                                                            \
  do {                                                                                                       \
    if (!(condition)) {                                                                                      \
      std::fprintf(stderr, "gesweep: internal error at %s:%d: failed %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                                          \
    }                                                                                                        \
  } while (false)

/// Marks a point the code cannot reach, such as the end of a switch that covers every value of an
/// enum: aborts with file and line instead of returning a made-up value. A value outside the enum
/// (a cast from a corrupt integer) is a broken invariant, not bad input.
#define GESWEEP_UNREACHABLE()                                                                      \
  do {                                                                                             \
    std::fprintf(stderr, "gesweep: internal error at %s:%d: reached unreachable code\n", __FILE__, \
                 __LINE__);                                                                        \
    std::abort();                                                                                  \
  } while (false)

}  // namespace gesweep
