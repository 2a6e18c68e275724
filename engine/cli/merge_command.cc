// gesweep merge: merges shard archives into one (docs/sweep.md, "Sharding and merge").
//   gesweep merge A.h5 B.h5 ... -o ALL.h5 [--copy] [--force]
// Default: a virtual archive over the shard files (nothing copied; they must stay where they are);
// --copy: a self-contained archive, chunks copied raw.
#include <iomanip>
#include <iostream>

#include "engine/archive/archive_merge.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/common/errors.h"

namespace gesweep::cli {
namespace {

struct MergeFlags {
  std::vector<std::string> inputs;
  std::string output;
  bool force = false;
  bool copy = false;
  bool quiet = false;
  DescribedFlags described{{{"quiet", "-q"}}};

  /// The switches, whose flag is their key's name (DescribedFlags, added by CommandWith); the
  /// archives and -o are added by hand.
  template <class V>
  void Describe(V& v) {
    v(Field("force", &force).Doc("Replace an existing output archive"));
    v(Field("copy", &copy)
          .Doc("Copy every chunk into a self-contained archive (default: a virtual archive over the shard "
               "files, which must then stay where they are)"));
    v(Field("quiet", &quiet).Doc("No summary line"));
  }
};

int Merge(const MergeFlags& flags) {
  std::vector<std::filesystem::path> inputs(flags.inputs.begin(), flags.inputs.end());
  std::string command_line = "gesweep merge";
  for (const auto& input : flags.inputs) command_line += " " + input;
  command_line += " -o " + flags.output + (flags.copy ? " --copy" : "") + (flags.force ? " --force" : "");
  return GuardArchive([&] {
    const MergeReport report = MergeArchives(inputs, flags.output, flags.force, command_line,
                                             flags.copy ? MergeKind::kCopy : MergeKind::kVirtual);
    if (!flags.quiet) {
      std::cerr << "gesweep: merged " << report.shards << " shard" << (report.shards > 1 ? "s" : "") << ": "
                << report.runs << " runs (" << report.runs_ok << " ok, " << report.runs_failed
                << " failed) -> " << flags.output;
      if (report.kind == MergeKind::kVirtual) {
        std::cerr << " (virtual)\ngesweep: " << flags.output
                  << " reads the shard files in place: keep them where "
                  << "they are (moving the directory with them is fine); `gesweep merge --copy` makes a "
                  << "self-contained archive\n";
      } else {
        std::cerr << " (" << report.chunks_copied << " chunks copied raw, " << std::fixed
                  << std::setprecision(1) << report.bytes_copied / 1e6 << " MB";
        if (report.chunks_rewritten) std::cerr << "; " << report.chunks_rewritten << " rewritten";
        std::cerr << ")\n";
      }
    }
    return 0;
  });
}

void AddMergeFlags(CLI::App& app, MergeFlags& flags) {
  app.add_option("archives", flags.inputs, "Shard archives (from gesweep run --shard i/N)")->required();
  app.add_option(
         "-o,--output", flags.output,
         "Merged archive to write (locked while it is written, as gesweep run locks its output; never a "
         "file the inputs read, the shards behind a virtual input included)")
      ->required();
}

const CommandRegistrar kRegistrar{CommandWith<MergeFlags>(
    "merge",
    "Merge shard archives of one study into one archive (virtual by default; --copy: self-contained), "
    "checking they cover the design exactly once",
    AddMergeFlags, Merge)};

}  // namespace
}  // namespace gesweep::cli
