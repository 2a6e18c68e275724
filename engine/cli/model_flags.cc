#include "engine/cli/model_flags.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "engine/cli/described_flags.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"

namespace gesweep::cli {
namespace {

std::string Trim(const std::string& text) {
  std::string trimmed = text;
  trimmed.erase(0, trimmed.find_first_not_of(" \t"));
  trimmed.erase(trimmed.find_last_not_of(" \t") + 1);
  return trimmed;
}

// A number a person typed: "" when it parses (into *value), else why not.
std::string NumberProblem(const std::string& text, double* value) {
  const std::string trimmed = Trim(text);
  if (trimmed == "inf" || trimmed == "infinity" || trimmed == "+inf") {
    *value = std::numeric_limits<double>::infinity();
    return "";
  }
  const char* begin = trimmed.data();
  const char* end = begin + trimmed.size();
  // from_chars takes no leading '+'; a person may write one.
  if (begin != end && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, *value);
  if (ec == std::errc::result_out_of_range && ptr == end) {
    const bool tiny = trimmed.find("e-") != std::string::npos || trimmed.find("E-") != std::string::npos;
    return tiny ? "is closer to 0 than a double can hold (about 2.2e-308); write 0 if 0 is meant"
                : "is past the largest magnitude a double can hold (about 1.8e308)";
  }
  if (trimmed.empty() || ec != std::errc() || ptr != end) return "expected a number";
  return "";
}

double ParseNumber(const std::string& token, const std::string& flag, bool allow_infinity) {
  double value = 0;
  const std::string problem = NumberProblem(token, &value);
  if (!problem.empty()) throw InputError("command line", flag, "'" + token + "'", problem);
  if (!std::isfinite(value) && !(allow_infinity && value > 0)) {
    throw InputError("command line", flag, "'" + token + "'",
                     allow_infinity ? "expected a finite number or inf" : "expected a finite number");
  }
  return value;
}

}  // namespace

ModelFlags::ModelFlags() : described_(std::make_unique<DescribedFlags>()) {}
ModelFlags::~ModelFlags() = default;

void ModelFlags::AddTo(CLI::App& app, bool aircraft_required) {
  auto* option =
      app.add_option("--aircraft", aircraft_path, "Aircraft file (TOML), e.g. studies/aircraft/ance.toml");
  if (aircraft_required) option->required();
  described_->Add(app, options);
}

ModelOptions ModelFlags::Options() const {
  described_->Apply();
  return options;
}

LongitudinalModel ModelFlags::BuildModel() const {
  const ModelOptions options = Options();
  return LongitudinalModel(LoadAircraftFile(aircraft_path), options);
}

std::vector<double> ParseNumberList(const std::string& text, const std::string& flag, bool allow_infinity) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string token;
  while (std::getline(stream, token, ',')) values.push_back(ParseNumber(token, flag, allow_infinity));
  if (values.empty()) throw InputError("command line", flag, "''", "expected at least one number");
  return values;
}

std::vector<double> ParseRange(const std::string& text, const std::string& flag) {
  if (text.find(':') == std::string::npos) return ParseNumberList(text, flag, false);
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string token;
  while (std::getline(stream, token, ':')) parts.push_back(token);
  if (parts.size() != 3) throw InputError("command line", flag, "'" + text + "'", "expected a:b:n");
  const double a = ParseNumber(parts[0], flag, false);
  const double b = ParseNumber(parts[1], flag, false);
  const double n = ParseNumber(parts[2], flag, false);
  if (n < 1 || n != std::floor(n) || n > 1e6) {
    throw InputError("command line", flag, "'" + text + "'", "expected a:b:n with a whole n from 1 to 1e6");
  }
  const int count = static_cast<int>(n);
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) values.push_back(count == 1 ? a : a + (b - a) * i / (count - 1));
  return values;
}

void RequireWithinLimit(const std::vector<double>& values, const std::string& limit,
                        const std::string& flag) {
  for (double value : values) CheckInputLimit(limit, value, "command line", flag);
}

CLI::Option* AddLimitedOption(CLI::App& app, const std::string& flag, double& value, const std::string& limit,
                              const std::string& description) {
  const InputLimit& range = RequireInputLimit(limit);
  CLI::Option* option = app.add_option(flag, value, description);
  // The check runs on the text, before CLI11 converts it, so that an overflow is named as one.
  // Its message is a whole InputError line; main.cc prints it as such.
  option->check(CLI::Validator(
      [flag, limit](std::string& text) -> std::string {
        double number = 0;
        std::string problem = NumberProblem(text, &number);
        if (problem.empty()) problem = LimitProblem(RequireInputLimit(limit), number);
        if (problem.empty()) return "";
        return InputError("command line", flag, text, problem).what();
      },
      DescribeLimit(range), "LIMIT:" + limit));
  return option;
}

CLI::Validator ExactIntegerValidator(const std::string& flag, const std::string& limit, double type_maximum) {
  const InputLimit& range = RequireInputLimit(limit);
  GESWEEP_DEMAND(range.whole && range.maximum <= type_maximum);
  // Digits within the range only, so CLI11's own conversion of the text into the field is exact.
  return CLI::Validator(
      [flag, limit](std::string& text) -> std::string {
        try {
          ParseExactInteger(text, limit, "command line", flag);
        } catch (const InputError& error) {
          return error.what();
        }
        return "";
      },
      DescribeLimit(range), "LIMIT:" + limit);
}

std::string FormatNumber(double value, int significant) {
  if (significant == 10) return ShortNumber(value);
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::ostringstream out;
  out.precision(significant);
  out << value;
  return out.str();
}

}  // namespace gesweep::cli
