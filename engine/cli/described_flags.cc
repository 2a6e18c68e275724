#include "engine/cli/described_flags.h"

#include <algorithm>
#include <cctype>

namespace gesweep::cli {

std::string FlagName(std::string_view key) {
  std::string flag = "--" + std::string(key);
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

DescribedFlags::Entry& DescribedFlags::NewEntry(std::string_view key) {
  GESWEEP_DEMAND(
      std::none_of(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; }));
  return entries_.emplace_back(Entry{std::string(key), {}, {}});
}

namespace {

bool IsShortName(std::string_view flag) { return flag.size() == 2 && flag[0] == '-' && flag[1] != '-'; }

}  // namespace

std::vector<std::string> DescribedFlags::AliasesOf(std::string_view key) const {
  std::vector<std::string> names;
  for (const FlagAlias& alias : aliases_) {
    if (alias.key == key && !IsShortName(alias.flag)) names.emplace_back(alias.flag);
  }
  return names;
}

std::string DescribedFlags::WithShortName(std::string_view key, const std::string& flag) const {
  for (const FlagAlias& alias : aliases_) {
    if (alias.key == key && IsShortName(alias.flag)) return std::string(alias.flag) + "," + flag;
  }
  return flag;
}

std::string DescribedFlags::Help(const FieldAttributes& attributes, const std::string& default_text,
                                 bool required) {
  std::string help(attributes.doc);
  // A NaN default or an empty list means "unset": the description says what applies then.
  if (!required && default_text != "nan" && !default_text.empty()) help += "; default " + default_text;
  return help;
}

std::string DescribedFlags::ListText(const std::vector<std::string>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) text += (i > 0 ? "," : "") + values[i];
  return text;
}

std::string DescribedFlags::ListText(const std::vector<double>& values) {
  std::vector<std::string> texts;
  texts.reserve(values.size());
  for (double value : values) texts.push_back(FieldNumberText(value));
  return ListText(texts);
}

CLI::Option* DescribedFlags::AddNumber(CLI::App& app, const std::string& flag, double& slot,
                                       const FieldAttributes& attributes, const std::string& help) {
  if (!attributes.limit.empty())
    return AddLimitedOption(app, flag, slot, std::string(attributes.limit), help);
  return app.add_option(flag, slot, help);
}

CLI::Option* DescribedFlags::AddChoice(CLI::App& app, const std::string& flag, std::string& slot,
                                       const std::string& help,
                                       const std::function<bool(const std::string&)>& known,
                                       const std::string& choices) {
  CLI::Option* option = app.add_option(flag, slot, help);
  // A whole InputError line, as AddLimitedOption's checks (main.cc prints it as such).
  option->check(CLI::Validator(
      [flag, known, choices](std::string& text) -> std::string {
        if (known(text)) return "";
        return InputError("command line", flag, "'" + text + "'", "expected " + choices).what();
      },
      choices, "CHOICE:" + flag));
  return option;
}

void DescribedFlags::AddNamedArray(CLI::App& app, const FieldAttributes& a, double* values) {
  const std::size_t count = a.components.size();
  std::string order, defaults;
  for (std::size_t c = 0; c < count; ++c) {
    order += (c ? "," : "") + std::string(a.components[c].name);
    defaults += (c ? "," : "") + FieldNumberText(values[c] / a.scale);
  }
  std::string doc(a.doc);
  const std::string_view placeholder = "<component>";
  if (const std::size_t at = doc.find(placeholder); at != std::string::npos)
    doc.replace(at, placeholder.size(), "<name>");
  const std::string help = std::to_string(count) + " comma-separated numbers, one per <name> in the order " +
                           order + ": " + doc + "; default " + defaults;
  Entry& entry = NewEntry(a.key);
  const std::string flag = FlagName(a.key);
  std::string& slot = texts_.emplace_back();
  entry.options.push_back(app.add_option(flag, slot, help));
  entry.names.push_back(flag);
  appliers_.push_back([values, count, order, flag, scale = a.scale, &slot] {
    if (slot.empty()) return;
    const std::vector<double> numbers = ParseNumberList(slot, flag, false);
    if (numbers.size() != count) {
      throw InputError(
          "command line", flag, "'" + slot + "'",
          "expected " + std::to_string(count) + " comma-separated numbers in the order " + order);
    }
    for (std::size_t c = 0; c < count; ++c) values[c] = numbers[c] * scale;
  });
}

void DescribedFlags::Apply() const {
  for (const auto& apply : appliers_) apply();
}

std::string DescribedFlags::FlagOf(std::string_view key) const {
  for (const Entry& entry : entries_) {
    if (entry.key != key) continue;
    for (std::size_t i = 0; i < entry.options.size(); ++i) {
      if (entry.options[i]->count() > 0) return entry.names[i];
    }
    return entry.names.front();
  }
  return std::string(key);
}

const std::vector<CLI::Option*>& DescribedFlags::OptionsOf(std::string_view key) const {
  for (const Entry& entry : entries_) {
    if (entry.key == key) return entry.options;
  }
  GESWEEP_UNREACHABLE();
}

namespace {

bool IsKeyCharacter(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }

// Replaces every whole-word "<key> = " in `text` by "<flag> = ".
void ReplaceKey(std::string& text, const std::string& key, const std::string& flag) {
  const std::string from = key + " = ";
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) {
    if (at > 0 && IsKeyCharacter(text[at - 1])) {
      at += from.size();
      continue;
    }
    text.replace(at, key.size(), flag);
    at += flag.size();
  }
}

}  // namespace

void DescribedFlags::Rethrow(const InputError& error) const {
  std::string expected = error.expected();
  for (const Entry& entry : entries_) ReplaceKey(expected, entry.key, FlagOf(entry.key));
  throw InputError("command line", FlagOf(error.key()), error.value(), expected);
}

}  // namespace gesweep::cli
