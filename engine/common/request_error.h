#pragma once
/// An InputError about a request that says what would fix it, in words a front end spells in its own
/// terms (docs/architecture.md, "Names of the command line"). Below engine/cli errors name the
/// request's fields ("where", "output"), never the CLI's flags; a remedy is a word such as "force",
/// "resume_or_force" or "no_write", with an argument where the hint needs one (the shard of
/// "resume_shard"). engine/cli/request_names.cc words each remedy as a hint.

#include <string>
#include <utility>

#include "engine/common/errors.h"

namespace gesweep {

/// Bad input in a request, with the remedy a front end offers. Its what() is the message without
/// the hint; the front end appends (or, for a few, prefixes) its wording.
class RequestError : public InputError {
 public:
  /// As InputError; `remedy` empty when the message says it all.
  RequestError(std::string source, std::string key, std::string value, std::string expected,
               std::string remedy, std::string remedy_argument = "")
      : InputError(std::move(source), std::move(key), std::move(value), std::move(expected)),
        remedy_(std::move(remedy)),
        remedy_argument_(std::move(remedy_argument)) {}

  const std::string& remedy() const { return remedy_; }
  const std::string& remedy_argument() const { return remedy_argument_; }

 private:
  std::string remedy_, remedy_argument_;
};

}  // namespace gesweep
