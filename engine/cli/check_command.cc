// gesweep check: the check every gesweep command makes of an archive before it reads a value, for the
// readers outside the engine (scripts/report; docs/report.md, "One reader"):
//   gesweep check ARCHIVE... [--format text|json]
// A sweep's archive is opened as query and boundary open it (ArchiveReader::Open: the file, its
// layout, a virtual archive's shard files and theirs); a subset-simulation archive as `gesweep risk`
// reads it (ReadRiskArchive: its kind, version, evaluations and estimates). json: one object per
// archive, in the order given: path, kind ("runs" or "subset_simulation"), snapshot (a sweep is writing
// it, or its writer died), virtual, notes (what could not be checked). The first archive that fails
// ends the command with one line naming it (exit 1), before anything is printed for the others.
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "engine/archive/archive_reader.h"
#include "engine/archive/subset_archive.h"
#include "engine/cli/command.h"

namespace gesweep::cli {
namespace {

struct CheckFlags {
  std::vector<std::string> archives;
  std::string format = "text";
};

// What `gesweep check` says of one archive that passed.
struct Checked {
  std::string path;
  std::string kind;
  bool snapshot = false;
  bool is_virtual = false;
  std::vector<std::string> notes;
};

Checked CheckOne(const std::string& path) {
  Checked checked{path, "runs", false, false, {}};
  // Only a regular file is probed for its kind (a FIFO would block the probe; the reader refuses it).
  if (std::filesystem::is_regular_file(path) && risk::IsRiskArchive(path)) {
    (void)risk::ReadRiskArchive(path, false);
    checked.kind = "subset_simulation";
    return checked;
  }
  const ArchiveReader reader = ArchiveReader::Open(path);
  checked.snapshot = reader.snapshot();
  checked.is_virtual = reader.is_virtual();
  checked.notes = reader.notes();
  return checked;
}

int RunCheck(const CheckFlags& flags) {
  RequireFormat(flags.format, {"text", "json"});
  return GuardArchive([&] {
    std::vector<Checked> all;
    all.reserve(flags.archives.size());
    for (const std::string& path : flags.archives) all.push_back(CheckOne(path));
    if (flags.format == "json") {
      nlohmann::ordered_json out = nlohmann::ordered_json::array();
      for (const Checked& c : all) {
        out.push_back({{"path", c.path},
                       {"kind", c.kind},
                       {"snapshot", c.snapshot},
                       {"virtual", c.is_virtual},
                       {"notes", c.notes}});
      }
      std::cout << out.dump(2) << "\n";
      return 0;
    }
    for (const Checked& c : all) {
      std::cout << c.path << ": " << (c.kind == "runs" ? "a sweep's archive" : "a subset-simulation archive")
                << (c.is_virtual ? ", virtual (gesweep merge)" : "")
                << (c.snapshot ? ", being written or left unclosed (read as a snapshot)" : "") << "\n";
      for (const std::string& note : c.notes) std::cout << "note: " << note << "\n";
    }
    return 0;
  });
}

void AddCheckFlags(CLI::App& app, CheckFlags& flags) {
  app.add_option("archives", flags.archives, "the archives to check (ARCHIVE...)")->required();
  app.add_option("--format", flags.format, "text (default) or json");
}

const CommandRegistrar kRegistrar{CommandWith<CheckFlags>(
    "check",
    "Check archives as every command does before it reads a value, and say what each is (docs/report.md)",
    AddCheckFlags, RunCheck)};

}  // namespace
}  // namespace gesweep::cli
