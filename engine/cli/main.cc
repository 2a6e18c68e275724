// The `gesweep` command: builds the CLI11 app from the registered subcommands, runs the chosen one,
// and turns a person's bad input into one line on stderr and exit code 2.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <set>
#include <string>

#include "engine/archive/archive_identity.h"
#include "engine/cli/command.h"
#include "engine/cli/failure_text.h"
#include "engine/cli/request_names.h"
#include "engine/common/errors.h"
#include "engine/common/notes.h"

namespace gesweep::cli {
std::vector<Command>& CommandRegistry() {
  static std::vector<Command> registry;
  return registry;
}
}  // namespace gesweep::cli

namespace {

// `gesweep --list-flags` (hidden): one line per option of every subcommand, tab-separated:
// subcommand, its names (comma-separated, as in --help), "switch" (takes no value), "positional" or
// "value", "hidden" for an alias or "shown", and the name of its check ("LIMIT:<limits-table entry>"
// for a flag checked against the table, "CHOICE:<flag>" for a named choice, "" for none).
void ListFlags(const std::vector<std::pair<CLI::App*, std::function<int()>>>& actions) {
  for (const auto& [sub, action] : actions) {
    for (const CLI::Option* option : sub->get_options()) {
      const std::vector<std::string>& long_names = option->get_lnames();
      if (std::find(long_names.begin(), long_names.end(), "help") != long_names.end()) continue;
      std::string names;
      for (const std::string& s : option->get_snames()) names += (names.empty() ? "-" : ",-") + s;
      for (const std::string& l : option->get_lnames()) names += (names.empty() ? "--" : ",--") + l;
      if (names.empty()) names = option->get_name(true);  // a positional (get_name is "" when hidden)
      if (names.empty()) continue;
      const char* kind =
          option->get_positional() && option->get_lnames().empty()
              ? "positional"
              : (option->get_items_expected_max() == 0 || option->get_type_size_max() == 0 ? "switch"
                                                                                           : "value");
      std::string check;
      try {
        check = const_cast<CLI::Option*>(option)->get_validator(0)->get_name();
      } catch (const CLI::OptionNotFound&) {
      }
      std::cout << sub->get_name() << "\t" << names << "\t" << kind << "\t"
                << (option->get_group().empty() ? "hidden" : "shown") << "\t" << check << "\n";
    }
  }
}

// Builds the CLI11 app, parses the command line and runs the chosen subcommand: its exit code, or 2
// for a bad command line (one line on stderr). What it throws (a command's InputError, a failure
// nothing caught) main turns into one line.
int Run(int argc, char** argv) {
  using gesweep::cli::CommandRegistry;
  CLI::App app{
      "gesweep: batch parametric and sensitivity studies of airplane longitudinal dynamics "
      "in ground effect"};
  app.require_subcommand(1);
  app.footer(
      "Every number a flag or a study file takes has one allowed range, with its reason: gesweep limits "
      "prints the table (docs/limits.md); each flag's range also shows beside it in SUBCOMMAND --help.");
  app.set_version_flag("--version",
                       std::string("gesweep ") + GESWEEP_VERSION + " (" + GESWEEP_GIT_COMMIT + ")");
  auto& registry = CommandRegistry();
  std::sort(registry.begin(), registry.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (auto& command : registry) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    actions.emplace_back(sub, command.setup(*sub));
  }
  // Hidden: every flag of every subcommand, for tests/cli/every_flag_test.py (one line each).
  if (argc == 2 && std::string(argv[1]) == "--list-flags") {
    ListFlags(actions);
    return 0;
  }
  if (argc > 1 && argv[1][0] != '-') {
    const std::string word = argv[1];
    std::string names;
    bool known = false;
    for (const auto& command : registry) {
      known = known || command.name == word;
      names += (names.empty() ? "" : ", ") + command.name;
    }
    if (!known) {
      std::cerr << "gesweep: error: unknown subcommand '" << word << "' (expected one of: " << names << ")\n";
      return 2;
    }
  }
  using gesweep::EscapeForMessage;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::string text = e.what();
    // A limited flag's check (AddLimitedOption) returns a whole InputError line; CLI11 puts the
    // option's name in front of it.
    const auto whole = text.find("command line: ");
    if (dynamic_cast<const CLI::ValidationError*>(&e) != nullptr && whole != std::string::npos) {
      text = text.substr(whole);
    }
    std::cerr << "gesweep: error: " << EscapeForMessage(text) << "\n";
    return 2;
  }
  for (auto& [sub, action] : actions) {
    if (sub->parsed()) return action();
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using gesweep::EscapeForMessage;
  // What a reader could not check (an archive merged before identities), an older name a study used:
  // one line each, once.
  auto note = [](const std::string& text) {
    static std::set<std::string> shown;
    if (shown.insert(text).second) std::cerr << "gesweep: note: " << EscapeForMessage(text) << "\n";
  };
  gesweep::archive::SetArchiveNoteHandler(note);
  gesweep::SetNoteHandler(note);
  try {
    return Run(argc, argv);
  } catch (...) {
    // One line and its exit code (failure_text.h): 2 for a person's bad input, 1 otherwise.
    std::string line;
    const int code = gesweep::cli::FailureLine(std::current_exception(), line);
    std::cerr << "gesweep: error: " << line << "\n";
    return code;
  }
}
