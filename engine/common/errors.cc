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
  // One printable line, always: file names, keys, values and a parser's description are a person's
  // text and may carry line breaks, terminal escape sequences or broken UTF-8.
  return EscapeForMessage(message);
}

const char kHex[] = "0123456789abcdef";

void AppendHexByte(std::string& out, unsigned char byte, bool unicode) {
  out.push_back('\\');
  if (unicode) {
    out.push_back('u');
    out.push_back('0');
    out.push_back('0');
  } else {
    out.push_back('x');
  }
  out.push_back(kHex[byte >> 4]);
  out.push_back(kHex[byte & 0xF]);
}

// Length of the valid UTF-8 sequence starting at text[i] (2 to 4), or 0 when it is not one
// (RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF).
std::size_t Utf8SequenceLength(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  std::size_t length = 0;
  unsigned char low = 0x80, high = 0xBF;  // allowed range of the second byte
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    if (lead == 0xE0) low = 0xA0;
    if (lead == 0xED) high = 0x9F;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  }
  return length;
}

}  // namespace

std::string ShortNumber(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

std::string EscapeForMessage(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x80) {
      if (byte == '\n' || byte == '\r' || byte == '\t') {
        out.push_back('\\');
        out.push_back(byte == '\n' ? 'n' : (byte == '\r' ? 'r' : 't'));
      } else if (byte < 0x20 || byte == 0x7F) {
        AppendHexByte(out, byte, false);
      } else {
        out.push_back(static_cast<char>(byte));
      }
      ++i;
      continue;
    }
    const std::size_t length = Utf8SequenceLength(text, i);
    if (length == 0) {
      AppendHexByte(out, byte, false);
      ++i;
      continue;
    }
    // U+0080..U+009F (C2 80..C2 9F) are the C1 controls; U+009B is the 8-bit CSI.
    if (length == 2 && byte == 0xC2 && static_cast<unsigned char>(text[i + 1]) <= 0x9F) {
      AppendHexByte(out, static_cast<unsigned char>(text[i + 1]), true);
    } else {
      for (std::size_t k = 0; k < length; ++k) out.push_back(text[i + k]);
    }
    i += length;
  }
  return out;
}

InputError::InputError(std::string source, std::string key, std::string value, std::string expected, int line)
    : std::runtime_error(Compose(source, key, value, expected, line)),
      source_(std::move(source)),
      key_(std::move(key)),
      value_(std::move(value)),
      expected_(std::move(expected)),
      line_(line) {}

}  // namespace gesweep
