#include "engine/common/toml_reader.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "engine/common/input_limits.h"
#include "engine/common/output_guard.h"

namespace gesweep {
namespace {

std::size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (same ? 0 : 1)});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

int NodeLine(const toml::node& node) {
  const auto& region = node.source();
  return static_cast<int>(region.begin.line);
}

}  // namespace

std::string NearestName(std::string_view key, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, key.size() / 3) + 1;
  for (const auto& candidate : candidates) {
    const std::size_t d = EditDistance(key, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

std::string ReadTextFile(const std::filesystem::path& path, std::string_view what) {
  const std::string noun(what);
  const std::string article = noun.find_first_of("aeiou") == 0 ? "an " : "a ";
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) {
    // e.g. a symlink loop ("Too many levels of symbolic links") or a permission problem on a folder.
    throw InputError(path.string(), "", "", "cannot read the " + noun + ": " + ec.message());
  }
  if (!std::filesystem::exists(status)) {
    throw InputError(path.string(), "", "", "cannot read the " + noun + ": no such file");
  }
  if (std::filesystem::is_directory(status)) {
    throw InputError(path.string(), "", "", "expected " + article + noun + ", found a directory");
  }
  if (!std::filesystem::is_regular_file(status)) {
    // A FIFO or a device could block or never end: refuse it at once.
    throw InputError(
        path.string(), "", "",
        "expected " + article + noun + ", found " + DescribeFileType(path) + " (not a regular file)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(path.string(), "", "", "cannot open the " + noun + " (permission denied?)");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path.string(), "", "", "read error");
  return text.str();
}

std::string MagnitudeProblem(const std::string& token) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size() || errno != ERANGE) return "";
  return value == 0.0 ? "is closer to 0 than a double can hold (about 2.2e-308); write 0 if 0 is meant"
                      : "is past the largest magnitude a double can hold (about 1.8e308)";
}

toml::table ParseToml(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::string description(e.description());
    // toml++ says a number too large for a double "could not be interpreted as a value": say why.
    const auto open = description.find('\'');
    const auto close = open == std::string::npos ? open : description.find('\'', open + 1);
    if (description.find("could not be interpreted") != std::string::npos && close != std::string::npos) {
      std::string token = description.substr(open + 1, close - open - 1);
      token.erase(std::remove(token.begin(), token.end(), '_'), token.end());  // TOML's digit separators
      const std::string magnitude = MagnitudeProblem(token);
      if (!magnitude.empty()) {
        throw InputError(source, "", "'" + token + "'", "the number " + magnitude,
                         static_cast<int>(e.source().begin.line));
      }
    }
    throw InputError(source, "", "", "TOML syntax error: " + description,
                     static_cast<int>(e.source().begin.line));
  }
}

std::string DescribeNode(const toml::node& node) {
  if (auto s = node.as_string()) return "\"" + s->get() + "\"";
  if (auto i = node.as_integer()) return std::to_string(i->get());
  if (auto f = node.as_floating_point()) return ShortNumber(f->get());
  if (auto b = node.as_boolean()) return b->get() ? "true" : "false";
  if (node.is_array()) return "[...]";
  if (node.is_table()) return "{...}";
  return "?";
}

std::string TomlSection::KeyOf(std::string_view key) const {
  if (prefix_.empty()) return std::string(key);
  return prefix_ + "." + std::string(key);
}

const toml::node* TomlSection::Node(std::string_view key) const { return table_->get(key); }

int TomlSection::LineOf(std::string_view key) const {
  if (const toml::node* node = Node(key)) return NodeLine(*node);
  return NodeLine(*table_);
}

void TomlSection::Fail(std::string_view key, std::string value, std::string expected) const {
  throw InputError(source_, KeyOf(key), std::move(value), std::move(expected), LineOf(key));
}

void TomlSection::RejectUnknownKeys(const std::vector<std::string>& allowed) const {
  for (const auto& [name, node] : *table_) {
    const std::string key(name.str());
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    const std::string near = NearestName(key, allowed);
    throw InputError(source_, KeyOf(key), "",
                     near.empty() ? "unknown key" : "unknown key (did you mean '" + near + "'?)",
                     NodeLine(node));
  }
}

TomlSection TomlSection::Section(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) Fail(key, "", "missing table [" + KeyOf(key) + "]");
  if (!node->is_table()) Fail(key, DescribeNode(*node), "expected a table");
  return TomlSection(*node->as_table(), source_, KeyOf(key));
}

std::optional<TomlSection> TomlSection::OptionalSection(std::string_view key) const {
  if (!Has(key)) return std::nullopt;
  return Section(key);
}

std::optional<double> TomlSection::OptionalNumber(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) return std::nullopt;
  double value;
  if (auto f = node->as_floating_point()) {
    value = f->get();
  } else if (auto i = node->as_integer()) {
    value = static_cast<double>(i->get());
  } else {
    Fail(key, DescribeNode(*node), "expected a number");
  }
  if (!std::isfinite(value)) Fail(key, DescribeNode(*node), "expected a finite number");
  return value;
}

std::optional<double> TomlSection::OptionalLimitedNumber(std::string_view key,
                                                         std::string_view limit_name) const {
  const auto value = OptionalNumber(key);
  if (!value) return value;
  const std::string problem = LimitProblem(RequireInputLimit(limit_name), *value);
  if (!problem.empty()) Fail(key, DescribeNode(*Node(key)), problem);
  return value;
}

double TomlSection::Number(std::string_view key) const {
  auto value = OptionalNumber(key);
  if (!value) Fail(key, "", "missing key, expected a number");
  return *value;
}

double TomlSection::PositiveNumber(std::string_view key) const {
  const double value = Number(key);
  if (!(value > 0.0)) Fail(key, DescribeNode(*Node(key)), "expected a number > 0");
  return value;
}

std::optional<std::string> TomlSection::OptionalString(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) return std::nullopt;
  if (auto s = node->as_string()) return s->get();
  Fail(key, DescribeNode(*node), "expected a string");
}

std::string TomlSection::String(std::string_view key) const {
  auto value = OptionalString(key);
  if (!value) Fail(key, "", "missing key, expected a string");
  return *value;
}

std::optional<bool> TomlSection::OptionalBool(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) return std::nullopt;
  if (auto b = node->as_boolean()) return b->get();
  Fail(key, DescribeNode(*node), "expected true or false");
}

std::optional<long long> TomlSection::OptionalInteger(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) return std::nullopt;
  if (auto i = node->as_integer()) return static_cast<long long>(i->get());
  Fail(key, DescribeNode(*node), "expected an integer");
}

std::vector<double> TomlSection::NumberArray(std::string_view key) const {
  const toml::node* node = Node(key);
  if (!node) Fail(key, "", "missing key, expected an array of numbers");
  const toml::array* array = node->as_array();
  if (!array) Fail(key, DescribeNode(*node), "expected an array of numbers");
  std::vector<double> values;
  values.reserve(array->size());
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::node& element = *array->get(i);
    double value;
    if (auto f = element.as_floating_point()) {
      value = f->get();
    } else if (auto n = element.as_integer()) {
      value = static_cast<double>(n->get());
    } else {
      throw InputError(source_, KeyOf(key) + "[" + std::to_string(i) + "]", DescribeNode(element),
                       "expected a number", NodeLine(element));
    }
    if (!std::isfinite(value)) {
      throw InputError(source_, KeyOf(key) + "[" + std::to_string(i) + "]", DescribeNode(element),
                       "expected a finite number", NodeLine(element));
    }
    values.push_back(value);
  }
  return values;
}

}  // namespace gesweep
