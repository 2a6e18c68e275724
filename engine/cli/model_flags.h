#pragma once
/// Flags shared by every subcommand that builds a model: --aircraft and the model options of
/// docs/model.md, one flag per field of ModelOptions::Describe (--no-h-derivatives, --cdh,
/// --interpolation, --cg-shift-over-chord).

#include <CLI/CLI.hpp>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "engine/dynamics/longitudinal_model.h"

namespace gesweep::cli {

class DescribedFlags;

struct ModelFlags {
  ModelFlags();
  ~ModelFlags();
  ModelFlags(const ModelFlags&) = delete;  // its flags write into `options`
  ModelFlags& operator=(const ModelFlags&) = delete;

  std::string aircraft_path;
  ModelOptions options;  // its described fields are flags; defaults as the struct's

  /// Adds the flags; `aircraft_required` makes --aircraft mandatory.
  void AddTo(CLI::App& app, bool aircraft_required = true);
  /// Loads the aircraft and builds the model; throws InputError on bad values.
  LongitudinalModel BuildModel() const;
  /// The options alone, with the flags given (each checked as it was parsed).
  ModelOptions Options() const;

 private:
  std::unique_ptr<DescribedFlags> described_;
};

/// Parses a comma-separated list of numbers given to `flag` ("inf" allowed when allow_infinity).
/// A number past a double's magnitude (about 1.8e308) is refused as such, not as "not a number".
std::vector<double> ParseNumberList(const std::string& text, const std::string& flag, bool allow_infinity);

/// Parses "a:b:n" (n ≥ 1 evenly spaced values from a to b) or a single number or a comma list.
std::vector<double> ParseRange(const std::string& text, const std::string& flag);

/// Throws InputError naming `flag` unless every value is within the limits table's entry `limit`
/// (engine/common/input_limits.h).
void RequireWithinLimit(const std::vector<double>& values, const std::string& limit, const std::string& flag);

/// Adds a number flag bound to `value` whose values must be within the limits table's entry `limit`:
/// the range shows in --help after the description, and a value outside it, a text that is not a
/// number, or a number past a double's magnitude is refused with one line (exit 2) naming the flag,
/// the value and the range.
CLI::Option* AddLimitedOption(CLI::App& app, const std::string& flag, double& value, const std::string& limit,
                              const std::string& description);

/// The check of AddExactIntegerOption (its message is a whole InputError line, as AddLimitedOption's).
/// `type_maximum` is the largest value of the flag's field: the entry's maximum must not exceed it.
CLI::Validator ExactIntegerValidator(const std::string& flag, const std::string& limit, double type_maximum);

/// Adds a whole-number flag (a seed, a run index, a count) bound to `value`, parsed exactly by
/// ParseExactInteger against the limits table's whole entry `limit`: digits only, within the range
/// (shown in --help), else one line (exit 2) naming the flag, the text and the range.
template <class Integer>
CLI::Option* AddExactIntegerOption(CLI::App& app, const std::string& flag, Integer& value,
                                   const std::string& limit, const std::string& description) {
  CLI::Option* option = app.add_option(flag, value, description);
  option->check(ExactIntegerValidator(flag, limit, static_cast<double>(std::numeric_limits<Integer>::max())));
  return option;
}

/// Formats a double for table/CSV output: shortest round-trip form; "inf", "nan".
std::string FormatNumber(double value, int significant = 10);

}  // namespace gesweep::cli
