#pragma once
/// The command-line visitor of a described struct (engine/common/describe.h): one flag per field.
///
/// The mapping is mechanical: key `step_s` is flag `--step-s` (underscores become hyphens); a
/// boolean that defaults to false is a switch `--<key>`, one that defaults to true is `--no-<key>`;
/// an enum field takes one of its names; an integer field (a seed) a whole number; a list field
/// (ListValue) its values comma-separated, or the flag repeated, in place of the default list.
/// Integer fields of a result struct are never Add()ed: only settings structs are. A number flag is
/// checked against the field's limits-table range as it is parsed (AddLimitedOption), in the key's
/// unit. The help text is the field's description and its default (none for an empty list). A
/// command may keep older names of a flag as hidden aliases (FlagAlias), and give a switch or a count
/// a short name (`-q`), shown with it; messages name the flag the person typed.

#include <CLI/CLI.hpp>
#include <deque>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/cli/model_flags.h"
#include "engine/common/copy_rules.h"
#include "engine/common/describe.h"
#include "engine/common/described_values.h"
#include "engine/common/errors.h"

namespace gesweep::cli {

/// The flag of a key: "--" + key with '_' replaced by '-'.
std::string FlagName(std::string_view key);

/// An older flag name a command keeps for a field: `--dt-s` for step_s. For a boolean field the
/// alias is a switch with the same effect as the field's own (e.g. `--no-breakpoints`). A short name
/// of a switch or a count (a dash and one letter, `-q` for quiet) is not hidden: the help shows it with
/// the flag (`-q,--quiet`); a number or a choice has none (their messages name the long flag).
struct FlagAlias {
  std::string_view key;
  std::string_view flag;
};

/// The flags of the fields of one or more described objects of a command.
class DescribedFlags {
 public:
  explicit DescribedFlags(std::vector<FlagAlias> aliases = {}) : aliases_(std::move(aliases)) {}
  GESWEEP_NO_COPY(DescribedFlags);

  /// Adds a flag per command-line field of `object` (scope kEverywhere or kCommandLineOnly); the
  /// object's current values are the defaults. Keys in `required` are required flags. `object` must
  /// outlive Apply().
  template <class T>
  void Add(CLI::App& app, T& object, const std::vector<std::string_view>& required = {});

  /// After parsing: writes every flag given into its field (in the struct's unit).
  void Apply() const;

  /// The flag the person typed for `key` (an alias when it was given so), else FlagName(key); `key`
  /// itself when no flag has that key.
  std::string FlagOf(std::string_view key) const;

  /// The options of `key`'s flag and its aliases, for a command's constraints on them (`excludes`);
  /// GESWEEP_DEMAND that `key` has a flag.
  const std::vector<CLI::Option*>& OptionsOf(std::string_view key) const;

  /// Throws `error` again (source "command line") with its key and the keys inside its expectation
  /// ("duration_s = 30 s / step_s = ...") written as the flags the person typed.
  [[noreturn]] void Rethrow(const InputError& error) const;

 private:
  struct Entry {
    std::string key;
    std::vector<CLI::Option*> options;  // its own flag first, then its aliases
    std::vector<std::string> names;     // their names (CLI11 gives a hidden option none)
  };
  Entry& NewEntry(std::string_view key);
  std::vector<std::string> AliasesOf(std::string_view key) const;
  std::string WithShortName(std::string_view key, const std::string& flag) const;
  CLI::Option* AddNumber(CLI::App& app, const std::string& flag, double& slot,
                         const FieldAttributes& attributes, const std::string& help);
  CLI::Option* AddChoice(CLI::App& app, const std::string& flag, std::string& slot, const std::string& help,
                         const std::function<bool(const std::string&)>& known, const std::string& choices);
  static std::string Help(const FieldAttributes& attributes, const std::string& default_text, bool required);
  /// The flag of a setting's array (named_components): its numbers comma-separated in component
  /// order, written into `values` (as many as components, in the struct's unit) by Apply. Each is
  /// checked against the field's range by the command's validation, under its component's key.
  void AddNamedArray(CLI::App& app, const FieldAttributes& attributes, double* values);
  static std::string ListText(const std::vector<std::string>& values);
  static std::string ListText(const std::vector<double>& values);

  std::vector<FlagAlias> aliases_;
  std::deque<Entry> entries_;
  std::deque<double> numbers_;
  std::deque<std::string> texts_;
  std::deque<bool> switches_;
  std::vector<std::function<void()>> appliers_;

  // Add's visitor.
  struct Adder {
    DescribedFlags* self;
    CLI::App* app;
    const std::vector<std::string_view>* required;
    template <class U>
    void operator()(const Field<U>& field) {
      // A result's array or text: none.
      if constexpr (SettingValue<U> || ListValue<U>) {
        Visit(field, field.attributes());
      } else if constexpr (DoubleArray<U>) {
        if (field.attributes().named_components && InScope(field.attributes(), false))
          self->AddNamedArray(*app, field.attributes(), field.value()->data());
      }
    }
    template <class U>
    void Visit(const Field<U>& field, const FieldAttributes& a) {
      if (!InScope(a, false)) return;
      const bool is_required = std::find(required->begin(), required->end(), a.key) != required->end();
      Entry& entry = self->NewEntry(a.key);
      U* value = field.value();
      if constexpr (std::same_as<U, bool>) {
        // A switch that sets the field to the opposite of its default.
        const bool default_value = *value;
        bool& given = self->switches_.emplace_back(false);
        const std::string flag = (default_value ? "--no-" : "--") + FlagName(a.key).substr(2);
        const std::string help = default_value
                                     ? "Sets " + std::string(a.key) + " false; " + std::string(a.doc)
                                     : std::string(a.doc);
        entry.options.push_back(app->add_flag(self->WithShortName(a.key, flag), given, help));
        entry.names.push_back(flag);
        for (const std::string& alias : self->AliasesOf(a.key)) {
          entry.options.push_back(app->add_flag(alias, given, "same as " + flag)->group(""));
          entry.names.push_back(alias);
        }
        self->appliers_.push_back([value, default_value, &given] {
          if (given) *value = !default_value;
        });
      } else if constexpr (NamedEnum<U>) {
        std::string& slot = self->texts_.emplace_back(ToString(*value));
        const std::string help = Help(a, slot, is_required);
        auto known = [](const std::string& text) { return ParseEnum<U>(text).has_value(); };
        entry.options.push_back(self->AddChoice(*app, FlagName(a.key), slot, help, known, EnumChoices<U>()));
        entry.names.push_back(FlagName(a.key));
        for (const std::string& alias : self->AliasesOf(a.key)) {
          entry.options.push_back(
              self->AddChoice(*app, alias, slot, help, known, EnumChoices<U>())->group(""));
          entry.names.push_back(alias);
        }
        self->appliers_.push_back([value, &slot] { *value = *ParseEnum<U>(slot); });
      } else if constexpr (std::floating_point<U>) {
        double& slot = self->numbers_.emplace_back(*value / a.scale);
        const std::string help = Help(a, FieldNumberText(slot), is_required);
        entry.options.push_back(self->AddNumber(*app, FlagName(a.key), slot, a, help));
        entry.names.push_back(FlagName(a.key));
        for (const std::string& alias : self->AliasesOf(a.key)) {
          entry.options.push_back(
              self->AddNumber(*app, alias, slot, a, "same as " + FlagName(a.key))->group(""));
          entry.names.push_back(alias);
        }
        const double scale = a.scale;
        const std::vector<CLI::Option*> options = entry.options;
        self->appliers_.push_back([value, scale, &slot, options] {
          for (const CLI::Option* option : options) {
            if (option->count() > 0) *value = slot * scale;  // untouched defaults keep their exact value
          }
        });
      } else if constexpr (IntegerValue<U>) {
        // A count or a seed: parsed exactly against its whole entry of the limits table (digits
        // only, no wrap, no clamp: AddExactIntegerOption), then by CLI11 into the field itself.
        GESWEEP_DEMAND(!a.limit.empty());  // every integer flag has its range
        const std::string help = Help(a, std::to_string(*value), is_required);
        entry.options.push_back(AddExactIntegerOption(*app, self->WithShortName(a.key, FlagName(a.key)),
                                                      *value, std::string(a.limit), help));
        entry.names.push_back(FlagName(a.key));
      } else if constexpr (ListValue<U>) {
        // CLI11 parses the values into the field itself, replacing the default list.
        GESWEEP_DEMAND(a.limit.empty() && a.scale == 1.0);  // a list has neither (ListValue)
        const std::string help = Help(a, ListText(*value), is_required);
        entry.options.push_back(app->add_option(FlagName(a.key), *value, help)->delimiter(','));
        entry.names.push_back(FlagName(a.key));
      } else {
        static_assert(!sizeof(U*),
                      "a command-line field is a number, an integer, a bool, a named enum or a list");
      }
      if (is_required) entry.options.front()->required();
    }
  };
};

template <class T>
void DescribedFlags::Add(CLI::App& app, T& object, const std::vector<std::string_view>& required) {
  Adder adder{this, &app, &required};
  object.Describe(adder);
}

}  // namespace gesweep::cli
