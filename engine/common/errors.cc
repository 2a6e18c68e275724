#include "engine/common/errors.h"

#include <sstream>

namespace gesweep {
namespace {

std::string Compose(const std::string& source, const std::string& key, const std::string& value,
                    const std::string& expected, int line) {
  std::string message;
  message.reserve(source.size() + key.size() + value.size() + expected.size() + 24);
  message.append(source);
  if (line > 0) message.append(":").append(std::to_string(line));
  if (!key.empty()) message.append(": ").append(key);
  if (!value.empty()) message.append(" = ").append(value);
  message.append(": ").append(expected);
  // One line, always: a quoted value or a parser's description may carry line breaks.
  for (char& ch : message) {
    if (ch == '\n' || ch == '\r') ch = ' ';
  }
  return message;
}

}  // namespace

std::string ShortNumber(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

InputError::InputError(std::string source, std::string key, std::string value, std::string expected,
                       int line)
    : std::runtime_error(Compose(source, key, value, expected, line)),
      source_(std::move(source)),
      key_(std::move(key)),
      value_(std::move(value)),
      expected_(std::move(expected)),
      line_(line) {}

}  // namespace gesweep
