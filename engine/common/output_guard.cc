#include "engine/common/output_guard.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// stat() after following symlinks; false (with errno) when it fails.
bool Stat(const std::filesystem::path& path, struct stat* info) { return ::stat(path.c_str(), info) == 0; }

std::string TypeOf(mode_t mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

bool SameFile(const std::filesystem::path& a, const std::filesystem::path& b) {
  struct stat first {};
  struct stat second {};
  if (!Stat(a, &first) || !Stat(b, &second)) return false;
  return first.st_dev == second.st_dev && first.st_ino == second.st_ino;
}

std::string DescribeFileType(const std::filesystem::path& path) {
  struct stat info {};
  if (!Stat(path, &info)) return "";
  return TypeOf(info.st_mode);
}

void CheckOutputPath(const std::filesystem::path& output, OutputKind kind,
                     const std::vector<NamedInput>& inputs, const std::string& flag,
                     const std::vector<std::filesystem::path>& sidecars) {
  const std::string shown = output.string();
  for (const NamedInput& input : inputs) {
    if (input.path.empty()) continue;
    if (SameFile(output, input.path) && !input.read_by.empty()) {
      throw InputError("command line", flag, shown,
                       "is the " + input.role + " " + input.path.string() + " that the input " +
                           input.read_by +
                           " reads, so an input of this command; an output never replaces an input: choose "
                           "another path");
    }
    if (SameFile(output, input.path)) {
      const bool literal = output.lexically_normal() == input.path.lexically_normal();
      throw InputError(
          "command line", flag, shown,
          "is the " + input.role + " " + input.path.string() +
              (literal ? "" : " (the same file: a hard link or a symlink to it)") +
              ", an input of this command; an output never replaces an input: choose another path");
    }
    for (const auto& sidecar : sidecars) {
      if (SameFile(sidecar, input.path)) {
        throw InputError("command line", flag, shown,
                         "writing it would replace " + sidecar.string() + ", which is the " + input.role +
                             " " + input.path.string() + "; choose another path");
      }
    }
  }
  struct stat info {};
  if (!Stat(output, &info)) {
    const int error = errno;
    if (error == ENOENT) {
      // Absent, or a dangling symlink: the writer creates the file (a symlink is replaced, its
      // missing target is not created).
      return;
    }
    throw InputError("command line", flag, shown, std::string("cannot use it: ") + std::strerror(error));
  }
  if (kind == OutputKind::kFile && !S_ISREG(info.st_mode)) {
    if (S_ISDIR(info.st_mode)) {
      throw InputError("command line", flag, shown,
                       "is a directory; expected an archive file name such as out.h5");
    }
    throw InputError("command line", flag, shown,
                     "exists and is " + TypeOf(info.st_mode) +
                         ", not a regular file; an output is only ever written to a regular file");
  }
  if (kind == OutputKind::kDirectory && !S_ISDIR(info.st_mode)) {
    throw InputError(
        "command line", flag, shown,
        "exists and is " + TypeOf(info.st_mode) + "; expected a directory (or a new name) to write into");
  }
}

std::filesystem::path RequireOutputDirectory(const std::filesystem::path& output, const std::string& flag) {
  std::filesystem::path directory = output.parent_path();
  if (directory.empty()) directory = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec)) {
    throw InputError("command line", flag, output.string(),
                     "the directory " + directory.string() + " does not exist");
  }
  return directory;
}

void RequireRegularFile(const std::filesystem::path& path, const std::string& what) {
  const std::string shown = path.string();
  struct stat info {};
  if (!Stat(path, &info)) {
    const int error = errno;
    if (error == ENOENT) throw InputError(shown, "", "", "no such " + what);
    throw InputError(shown, "", "", "cannot read the " + what + ": " + std::strerror(error));
  }
  const std::string article = what.find_first_of("aeiou") == 0 ? "an " : "a ";
  if (S_ISDIR(info.st_mode)) throw InputError(shown, "", "", "is a directory, not " + article + what);
  if (!S_ISREG(info.st_mode)) {
    throw InputError(shown, "", "",
                     "is " + TypeOf(info.st_mode) + ", not a regular file (expected " + article + what +
                         "; a FIFO or a device could block or never end)");
  }
}

}  // namespace gesweep
