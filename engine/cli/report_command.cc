// gesweep report: an HTML report of one or more archives (docs/report.md, "gesweep report").
//   gesweep report ARCHIVE|DIR ... -o DIR
// Checks every input here (each must open as a gesweep archive), then runs scripts/report/report.py
// (matplotlib, h5py) with Debian's python3, which writes DIR/index.html and its figures beside it.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "engine/archive/archive_error.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/subset_archive.h"
#include "engine/cli/command.h"
#include "engine/cli/report_script.h"
#include "engine/common/errors.h"
#include "engine/common/output_guard.h"

extern char** environ;

namespace gesweep::cli {
namespace {

struct ReportFlags {
  std::vector<std::string> inputs;
  std::string output;
  std::string title;
  bool quiet = false;
};

// The archives named on the command line: files as given, directories as their *.h5 files.
std::vector<std::string> ExpandInputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> archives;
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (std::filesystem::is_directory(input, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : std::filesystem::directory_iterator(input, ec)) {
        if (entry.is_regular_file() && entry.path().extension() == ".h5")
          found.push_back(entry.path().string());
      }
      if (ec) throw InputError(input, "", "", "cannot list the directory: " + ec.message());
      if (found.empty()) throw InputError(input, "", "", "a directory without any archive (*.h5)");
      std::sort(found.begin(), found.end());
      archives.insert(archives.end(), found.begin(), found.end());
    } else {
      archives.push_back(input);
    }
  }
  // The same archive twice (e.g. a file and its directory) is reported once.
  std::vector<std::string> unique;
  for (const auto& a : archives) {
    const bool seen = std::any_of(unique.begin(), unique.end(), [&](const std::string& b) {
      std::error_code ec;
      return std::filesystem::equivalent(a, b, ec);
    });
    if (!seen) unique.push_back(a);
  }
  return unique;
}

// What the report writes in its directory (scripts/report/report.py): index.html through a
// temporary, and figures named <section>_*.png, which it also deletes from an earlier report.
bool ReportWrites(const std::string& name) {
  if (name == "index.html" || name == "index.html.partial") return true;
  if (name.size() < 4 || name.compare(name.size() - 4, 4, ".png") != 0) return false;
  for (const char* prefix : {"stability_", "root_", "open_", "landing_", "sensitivity_"}) {
    if (name.rfind(prefix, 0) == 0) return true;
  }
  return false;
}

int RunReport(const ReportFlags& flags) {
  const std::vector<std::string> archives = ExpandInputs(flags.inputs);
  const std::filesystem::path output(flags.output);
  std::vector<NamedInput> inputs;
  inputs.reserve(archives.size());
  for (const auto& path : archives) inputs.push_back({path, "input archive"});
  // Before any archive is read or anything written: the directory is a directory (or new), and
  // none of the files the report writes or deletes in it is an input.
  CheckOutputPath(output, OutputKind::kDirectory, inputs, "-o");
  std::error_code ec;
  for (const auto& input : inputs) {
    const std::filesystem::path name = input.path.filename();
    if (ReportWrites(name.string()) && SameFile(output / name, input.path)) {
      throw InputError("command line", "-o", flags.output,
                       "the report would replace " + (output / name).string() + ", the input archive " +
                           input.path.string() + "; choose another directory");
    }
  }
  const std::filesystem::path parent =
      output.has_parent_path() ? output.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(parent, ec)) {
    throw InputError("command line", "-o", flags.output,
                     "the directory " + parent.string() + " does not exist");
  }
  try {
    // The same validation as query and boundary (ArchiveReader::Open), or as `gesweep risk` for a
    // subset-simulation archive: a damaged or foreign archive is refused with one line (exit 2) before
    // the script starts or the directory is made.
    for (const auto& path : archives) {
      // Only a regular file is probed (a FIFO would block the probe; ArchiveReader::Open refuses it).
      if (std::filesystem::is_regular_file(path) && risk::IsRiskArchive(path)) {
        (void)risk::ReadRiskArchive(path, false);
      } else {
        ArchiveReader::Open(path);
      }
    }
  } catch (const ArchiveError& e) {
    std::cerr << "gesweep: error: " << EscapeForMessage(e.what()) << "\n";
    return 1;
  }
  const std::filesystem::path script = ReportScriptPath();
  if (!std::filesystem::is_regular_file(script, ec)) {
    throw InputError("environment", "GESWEEP_REPORT_SCRIPT", script.string(),
                     "the report script is missing (expected scripts/report/report.py of the source tree)");
  }
  const std::string python = ReportPython();
  std::vector<std::string> arguments = {python, script.string(), "-o", flags.output};
  if (!flags.title.empty()) {
    arguments.push_back("--title");
    arguments.push_back(flags.title);
  }
  if (flags.quiet) arguments.push_back("--quiet");
  arguments.push_back("--");
  arguments.insert(arguments.end(), archives.begin(), archives.end());
  std::vector<char*> argv;
  argv.reserve(arguments.size() + 1);  // and the terminating nullptr
  for (auto& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  std::cout.flush();
  const int spawn_error = posix_spawn(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ);
  if (spawn_error != 0) {
    throw InputError("environment", "GESWEEP_PYTHON", python,
                     "cannot run it (" + std::string(std::strerror(spawn_error)) +
                         "); expected Debian's /usr/bin/python3 with python3-h5py and python3-matplotlib");
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      std::cerr << "gesweep: error: waiting for the report script: " << std::strerror(errno) << "\n";
      return 1;
    }
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  std::cerr << "gesweep: error: the report script was stopped by signal " << WTERMSIG(status) << "\n";
  return 1;
}

void AddReportFlags(CLI::App& app, ReportFlags& flags) {
  app.add_option("archives", flags.inputs, "Archives (HDF5), or directories of archives (*.h5)")->required();
  app.add_option("-o,--output", flags.output, "Directory for index.html and its figures (created)")
      ->required();
  app.add_option("--title", flags.title, "Title of the page (default: from the studies)");
  app.add_flag("-q,--quiet", flags.quiet, "No progress lines");
}

const CommandRegistrar kRegistrar{
    CommandWith<ReportFlags>("report", "Write an HTML report (figures and tables) of one or more archives",
                             AddReportFlags, RunReport)};

}  // namespace
}  // namespace gesweep::cli
