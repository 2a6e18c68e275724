#pragma once
/// A failure no command caught, in the project's words (issue 26, item 6): what a library threw
/// (Boost.Math, the standard library, nlohmann::json) never reaches a person as the library's own
/// text ("Error in function boost::math::...", "std::bad_alloc", "[json.exception...]"). Bad input is
/// an InputError and an archive's I/O an ArchiveError, each with its own line; this is for the rest.

#include <exception>
#include <string>

namespace gesweep::cli {

/// One line saying what failed, in the project's words, with the library's detail kept only where it
/// is the operating system's (a file system error names the path and the system's reason).
std::string FailureInWords(const std::exception& error);

/// What `gesweep` prints after "gesweep: error: " for a failure that ends a command (`error`, from
/// std::current_exception()), escaped for one line, and the exit code: 2 for an InputError (its
/// request fields and remedies in the command line's words), 1 for an ArchiveError or anything else
/// (FailureInWords). main.cc prints every failure no command caught so; `gesweep risk --mpi` the one
/// its ranks agree on.
int FailureLine(const std::exception_ptr& error, std::string& line);

}  // namespace gesweep::cli
