#pragma once
/// The command line's names for the engine's request fields and remedies (docs/architecture.md,
/// "Names of the command line"). Below engine/cli an InputError about a request names the request's
/// field ("where", "group_by") and, where a different request would be accepted, a remedy word
/// ("force", "no_write"); the subcommand spells the field as its flag, and the CLI words the remedy
/// as a hint in its own terms, when it reports the error.

#include <map>
#include <optional>
#include <string>

#include "engine/common/errors.h"
#include "engine/common/request_error.h"

namespace gesweep::cli {

/// Request field -> the flag that fills it ("group_by" -> "--group-by").
using FlagNames = std::map<std::string, std::string>;

/// The flags of the request fields every subcommand spells alike: an error whose source is
/// "command line" and whose key is one of these is shown with the flag (main.cc).
const FlagNames& CommandLineFlags();

/// What was expected, with the command line's hint for the remedy the engine names
/// (RequestError::remedy, with its remedy_argument()); nullopt for a remedy it has no words for.
std::optional<std::string> WordRemedy(const RequestError& error);

/// `error` as the command line shows it: a key that is one of `flags` (by default, for an error
/// whose source is "command line", CommandLineFlags()) becomes its flag, the remedy of a RequestError
/// its hint. The result is a plain InputError, so that wording it twice adds nothing.
InputError ForCommandLine(const InputError& error);
InputError ForCommandLine(const InputError& error, const FlagNames& flags);

/// `error` as the Python module gesweep shows it (engine/python, docs/python.md): the key is the
/// request field, which is also the Python argument's name; the remedy of a RequestError is worded as
/// the keyword argument that gives it (force=True, resume=True), or, for a remedy with no Python
/// equivalent, as the command line words it.
InputError ForPython(const InputError& error);

}  // namespace gesweep::cli
