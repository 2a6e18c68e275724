#pragma once
/// The one check every command that writes a file makes before it touches anything (docs/reliability.md,
/// "Outputs never overwrite inputs"): an output path must not resolve to any input of the command --
/// the same file, a hard link to it or a symlink to it (compared by device and inode, after following
/// symlinks) -- and an output that exists must be a regular file (or a directory where a directory is
/// wanted). `gesweep run`, `merge` and `report` call it; `boundary --archive` and `sensitivity` write
/// into their input archive on purpose and check it with RequireRegularFile; `simulate` and `land`
/// write to stdout only.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace gesweep {

/// A file a command reads, with what it is for messages ("study file", "shard archive").
struct NamedInput {
  NamedInput(std::filesystem::path path_, std::string role_, std::string read_by_ = "")
      : path(std::move(path_)), role(std::move(role_)), read_by(std::move(read_by_)) {}
  std::filesystem::path path;
  std::string role;
  /// The input that reads this file when the command does not name it itself (a virtual archive's
  /// shard: "merged.h5"); empty for a file the command names.
  std::string read_by;
};

/// What a command writes at its output path.
enum class OutputKind {
  kFile,       ///< a regular file (an archive)
  kDirectory,  ///< a directory it fills (a report)
};

/// Whether `a` and `b` both exist and are the same file (same device and inode after following
/// symlinks): the same path, a hard link, or a symlink to it.
bool SameFile(const std::filesystem::path& a, const std::filesystem::path& b);

/// "a directory", "a character device", "a FIFO", ... for what `path` is; "a regular file" for one;
/// "" when it does not exist.
std::string DescribeFileType(const std::filesystem::path& path);

/// Throws InputError("command line", flag, output, ...) when
///  - `output`, or one of `sidecars` (other paths the writer creates, renames or deletes, such as
///    ARCHIVE.partial), is the same file as one of `inputs`;
///  - `output` exists and is not what `kind` wants (a FIFO, a device, a socket, a directory for a
///    file, a file for a directory), or is a symlink that cannot be followed (a loop).
/// Nothing is created or changed.
void CheckOutputPath(const std::filesystem::path& output, OutputKind kind,
                     const std::vector<NamedInput>& inputs, const std::string& flag,
                     const std::vector<std::filesystem::path>& sidecars = {});

/// D, the directory `output` is to be created in (its parent; "." for a bare name). Throws
/// InputError("command line", flag, output, "the directory D does not exist") unless it is a directory.
std::filesystem::path RequireOutputDirectory(const std::filesystem::path& output, const std::string& flag);

/// Throws InputError(path, "", "", ...) unless `path` exists and is a regular file (symlinks followed):
/// "no such file", "is a directory", "is a FIFO, not a regular file" (a FIFO or a device could block
/// a reader for ever or never end), "cannot read the archive: Too many levels of symbolic links".
/// `what` names it in messages, without an article ("archive", "study file").
void RequireRegularFile(const std::filesystem::path& path, const std::string& what);

}  // namespace gesweep
