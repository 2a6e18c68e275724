#include "engine/cli/failure_text.h"

#include <filesystem>
#include <new>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "engine/archive/archive_error.h"
#include "engine/cli/request_names.h"
#include "engine/common/errors.h"

namespace gesweep::cli {
namespace {

constexpr std::string_view kReport =
    "; this is a defect of gesweep, not of the input: please report it with the command line";

}  // namespace

std::string FailureInWords(const std::exception& error) {
  if (dynamic_cast<const std::bad_alloc*>(&error) != nullptr) {
    return "out of memory: the work asked for more memory than the machine gave (the limits on one run's "
           "work are in docs/limits.md; fewer --threads take less)";
  }
  if (const auto* fs = dynamic_cast<const std::filesystem::filesystem_error*>(&error)) {
    std::string text = "a file operation failed";
    if (!fs->path1().empty()) text += " on " + fs->path1().string();
    if (!fs->path2().empty()) text += " and " + fs->path2().string();
    return text + ": " + fs->code().message();
  }
  if (const auto* system = dynamic_cast<const std::system_error*>(&error)) {
    return "a system call failed: " + system->code().message();
  }
  if (dynamic_cast<const nlohmann::json::exception*>(&error) != nullptr) {
    return "an internal failure writing or reading JSON" + std::string(kReport);
  }
  // Boost.Math reports through std::domain_error, std::overflow_error, std::underflow_error and
  // evaluation_error (a std::runtime_error); the standard library through logic and runtime errors.
  if (dynamic_cast<const std::domain_error*>(&error) != nullptr ||
      dynamic_cast<const std::overflow_error*>(&error) != nullptr ||
      dynamic_cast<const std::underflow_error*>(&error) != nullptr ||
      dynamic_cast<const std::range_error*>(&error) != nullptr ||
      std::string_view(error.what()).find("boost::math") != std::string_view::npos) {
    return "a numerical failure: an internal computation had no valid result" + std::string(kReport);
  }
  return "an internal failure (" +
         std::string(dynamic_cast<const std::logic_error*>(&error) ? "logic" : "runtime") + " error)" +
         std::string(kReport);
}

int FailureLine(const std::exception_ptr& error, std::string& line) {
  try {
    std::rethrow_exception(error);
  } catch (const InputError& e) {
    // The engine names remedies ("force", "no_write"); the command line words them (request_names.h).
    line = EscapeForMessage(ForCommandLine(e).what());
    return 2;
  } catch (const ArchiveError& e) {
    // An archive's I/O the command did not catch: its own line (the archive and the cause).
    line = EscapeForMessage(e.what());
    return 1;
  } catch (const std::exception& e) {
    // Not a person's input and not caught by the command: one line in the project's words, never
    // a library's own text (issue 26, item 6), the I/O exit code.
    line = EscapeForMessage(FailureInWords(e));
    return 1;
  } catch (...) {
    // Not a std::exception (gesweep throws none; a library might): still one line and exit code 1,
    // never std::terminate.
    line = "an unexpected exception (not a std::exception)";
    return 1;
  }
}

}  // namespace gesweep::cli
