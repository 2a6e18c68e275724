#pragma once
/// The subcommand registry of the `gesweep` CLI. Each subcommand lives in its own file in engine/cli/
/// and registers itself with a static CommandRegistrar (usually of CommandWith<Flags>); main.cc
/// builds the CLI11 app from the registry. Subcommands parse, call the engine and print; they hold no
/// physics. Below: the shapes every command shares (registration, the --format check, the ARCHIVE
/// positional, the end on an archive it cannot use, the lock-and-open of a product command).

#include <CLI/CLI.hpp>
#include <concepts>
#include <exception>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/archive/archive_error.h"
#include "engine/archive/archive_lock.h"
#include "engine/archive/archive_reader.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/request_names.h"
#include "engine/common/enum_names.h"

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

namespace command_detail {
struct NoVisitor {
  template <class U>
  void operator()(const Field<U>&) {}
};
}  // namespace command_detail

/// A `Flags` struct that describes its own settings (engine/common/describe.h): a member template
/// `Describe` and a `DescribedFlags described` that makes their flags.
template <class Flags>
concept DescribedSettings = requires(Flags& flags, command_detail::NoVisitor& visitor) {
  flags.Describe(visitor);
  { flags.described } -> std::same_as<DescribedFlags&>;
};

/// The registration of a subcommand whose settings are one `Flags` struct (a fresh one per parse):
/// `add(app, flags)` adds its flags and positionals bound to the struct's members, `run(flags)` is
/// the action once parsed and returns the exit code. When `Flags` is DescribedSettings, the flags of
/// its described fields come after `add`'s, and are written into the struct before `run`. A command
/// file ends with
///
///     const CommandRegistrar kRegistrar{CommandWith<MergeFlags>("merge", "Merge shard archives ...",
///                                                               AddMergeFlags, Merge)};
template <class Flags>
Command CommandWith(std::string name, std::string description, void (*add)(CLI::App&, Flags&),
                    int (*run)(const Flags&)) {
  return Command{std::move(name), std::move(description), [add, run](CLI::App& app) -> std::function<int()> {
                   auto flags = std::make_shared<Flags>();
                   add(app, *flags);
                   if constexpr (DescribedSettings<Flags>) flags->described.Add(app, *flags);
                   return [flags, run] {
                     if constexpr (DescribedSettings<Flags>) flags->described.Apply();
                     return run(*flags);
                   };
                 }};
}

/// The --format of a command that prints a table for a person or JSON for a program: a described
/// choice (`Field("format", &format)`), so its flag, its help and its one-line refusal come from the
/// names table below, as every enum flag's do.
enum class TableOrJson { kAligned, kJson };

/// The --format of a command that prints a text report or JSON (a described choice, as TableOrJson).
enum class TextOrJson { kText, kJson };

}  // namespace gesweep::cli

namespace gesweep {
GESWEEP_ENUM_NAMES(cli::TableOrJson, {kAligned, "table"}, {kJson, "json"});
GESWEEP_ENUM_NAMES(cli::TextOrJson, {kText, "text"}, {kJson, "json"});
}  // namespace gesweep

namespace gesweep::cli {

/// Refuses a --format value that is not one of `choices` (exit 2), for the commands whose flags are
/// added by hand:
/// "command line: --format = 'xml': expected table, csv or json".
void RequireFormat(const std::string& format, std::initializer_list<std::string_view> choices);

/// The positional ARCHIVE of a command that reads one (required).
inline CLI::Option* AddArchiveArgument(CLI::App& app, std::string& archive, const std::string& description) {
  return app.add_option("archive", archive, description)->required();
}

/// How a command ends on an archive it cannot use (ArchiveError: unreadable, not an archive of this
/// format, locked): the message on one line of stderr, exit code 1.
inline int ArchiveFailure(const std::exception& error) {
  std::cerr << "gesweep: error: " << error.what() << "\n";
  return 1;
}

/// Runs a command's `body` (returning its exit code) the way every command that reads an archive
/// ends: an ArchiveError is ArchiveFailure (exit 1); an InputError passes on to main.cc, which prints
/// it (exit 2).
template <class Body>
int GuardArchive(Body&& body) {
  try {
    return body();
  } catch (const ArchiveError& e) {
    return ArchiveFailure(e);
  }
}

/// The same, and an InputError about a request field the command fills from its flags is shown
/// with the flag: `flags` maps the field to it (ForCommandLine; e.g. {"group_by", "--group-by"}).
template <class Body>
int GuardArchive(const FlagNames& flags, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    throw ForCommandLine(e, flags);
  } catch (const ArchiveError& e) {
    return ArchiveFailure(e);
  }
}

/// An archive a product command (dispersion, sensitivity) reads and then writes its /analysis
/// group into: the lock, held from before the read to after the write so that no sweep starts
/// writing meanwhile (none with no_write), and the open reader.
struct ProductArchive {
  std::optional<ArchiveLock> lock;
  ArchiveReader reader;
};

/// Opens `path` for the product command `command` ("dispersion"): claims it unless `no_write`
/// (a missing archive is reported as such by the reader, not as an unwritable lock file), and refuses
/// an archive a sweep is writing, or left unclosed, unless `no_write`.
ProductArchive OpenProductArchive(const std::string& path, bool no_write, std::string_view command);

}  // namespace gesweep::cli
