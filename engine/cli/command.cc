#include "engine/cli/command.h"

#include <filesystem>
#include <system_error>

#include "engine/common/errors.h"

namespace gesweep::cli {

void RequireFormat(const std::string& format, std::initializer_list<std::string_view> choices) {
  std::string expected;
  std::size_t i = 0;
  for (std::string_view choice : choices) {
    if (format == choice) return;
    expected += (i == 0 ? "" : (i + 1 == choices.size() ? " or " : ", ")) + std::string(choice);
    ++i;
  }
  throw InputError("command line", "--format", "'" + format + "'", "expected " + expected);
}

ProductArchive OpenProductArchive(const std::string& path, bool no_write, std::string_view command) {
  std::error_code ec;
  std::optional<ArchiveLock> lock;
  if (!no_write && std::filesystem::is_regular_file(path, ec)) {
    lock.emplace(
        ArchiveLock::Acquire(path, "run gesweep " + std::string(command) +
                                       " once it has finished, or pass --no-write to only print it"));
  }
  ArchiveReader reader = ArchiveReader::Open(path);
  if (reader.snapshot() && !no_write) {
    throw InputError(path, "", "",
                     "archive in use: a sweep is writing it, or the sweep that wrote it stopped without "
                     "closing it (finish it with `gesweep run STUDY -o " +
                         path + " --resume`); or pass --no-write");
  }
  return ProductArchive{std::move(lock), std::move(reader)};
}

}  // namespace gesweep::cli
