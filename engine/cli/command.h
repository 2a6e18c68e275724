#pragma once
/// The subcommand registry of the `gesweep` CLI. Each subcommand lives in its own file in engine/cli/
/// and registers itself with a static GESWEEP_REGISTER_COMMAND; main.cc builds the CLI11 app from the
/// registry. Subcommands parse, call the engine and print; they hold no physics.

#include <CLI/CLI.hpp>
#include <exception>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace gesweep::cli {

/// A subcommand: `setup` adds its options to `app` and returns the action to run once parsed.
/// The action returns the process exit code (0 ok, 2 bad input, 3 some runs failed).
struct Command {
  std::string name;
  std::string description;
  std::function<std::function<int()>(CLI::App& app)> setup;
};

/// All registered subcommands, in registration order.
std::vector<Command>& CommandRegistry();

/// Adds a command to the registry at static-initialisation time.
struct CommandRegistrar {
  explicit CommandRegistrar(Command command) { CommandRegistry().push_back(std::move(command)); }
};

/// How a command ends on an archive it cannot use (ArchiveError: unreadable, not an archive of this
/// format, locked): the message on one line of stderr, exit code 1.
inline int ArchiveFailure(const std::exception& error) {
  std::cerr << "gesweep: error: " << error.what() << "\n";
  return 1;
}

}  // namespace gesweep::cli
