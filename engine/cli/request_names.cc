#include "engine/cli/request_names.h"

namespace gesweep::cli {

namespace {

// Each remedy as the command line and the Python module (the keyword arguments of gesweep.run) word
// it: `before` what was expected, then `after`, in which "{}" stands for the remedy's argument. A
// remedy without Python words (python_after null) is worded there as on the command line.
struct Wording {
  const char* remedy;
  const char* before;
  const char* after;
  const char* python_after;
};
constexpr Wording kWordings[] = {
    {"describe_columns", "", "; gesweep query ARCHIVE --describe lists the columns", nullptr},
    {"fewer_groups", "", "; group by fewer columns, narrow --where, or raise --max-groups", nullptr},
    {"aggregate_sort", "with --group-by/--aggregate, ", "", nullptr},
    {"by_other_parameters", "", "; --by names the other swept parameters", nullptr},
    {"force", "", "; pass --force to replace it", "; pass force=True to replace it"},
    {"force_use", "", "; use --force to replace it", "; pass force=True to replace it"},
    {"force_or_other_output", "", "; use --force to replace it, or another -o",
     "; pass force=True to replace it, or another archive_path"},
    {"resume_or_force", "", "; pass --resume to continue it or --force to replace it",
     "; pass resume=True to continue it or force=True to replace it"},
    {"force_or_resume_nodes", "", "; pass --force to replace them or --resume with as many nodes", nullptr},
    {"resume_shard_first", "", "; finish it with `gesweep run ... --shard {} --resume` first",
     "; finish it with gesweep.run(..., shard=\"{}\", resume=True) first"},
    {"resume_shard", "", "; finish it with `gesweep run ... --shard {} --resume`",
     "; finish it with gesweep.run(..., shard=\"{}\", resume=True)"},
    {"resume_repairs", "", ": gesweep run STUDY -o {} --resume repairs it and goes on",
     ": gesweep.run(study, \"{}\", resume=True) repairs it and goes on"},
    {"finish_sweep", "", "; finish the sweep with `gesweep run STUDY -o {} --resume`",
     "; finish the sweep with gesweep.run(study, \"{}\", resume=True)"},
    {"merge_copy", "", " (gesweep merge --copy makes a self-contained archive)", nullptr},
    {"use_method", "", " (use --method {})", nullptr},
    {"no_write", "", " pass --no-write to only print {}", nullptr},
};

// The expectation of `error` worded for the command line (`python` false) or the Python module.
std::optional<std::string> Word(const RequestError& error, bool python) {
  for (const Wording& w : kWordings) {
    if (error.remedy() != w.remedy) continue;
    std::string after = python && w.python_after != nullptr ? w.python_after : w.after;
    if (const auto at = after.find("{}"); at != std::string::npos)
      after.replace(at, 2, error.remedy_argument());
    return w.before + error.expected() + after;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> WordRemedy(const RequestError& error) { return Word(error, false); }

InputError ForPython(const InputError& error) {
  const auto* request = dynamic_cast<const RequestError*>(&error);
  if (request == nullptr) return error;
  const std::optional<std::string> worded = Word(*request, true);
  if (!worded) return error;
  return InputError(error.source(), error.key(), error.value(), *worded, error.line());
}

const FlagNames& CommandLineFlags() {
  static const FlagNames flags = {
      {"where", "--where"},
      {"columns", "--columns"},
      {"sort", "--sort"},
      {"group_by", "--group-by"},
      {"aggregates", "--aggregate"},
      {"max_groups", "--max-groups"},
      {"by", "--by"},
      {"shard", "--shard"},
      {"output", "-o"},
  };
  return flags;
}

InputError ForCommandLine(const InputError& error) {
  static const FlagNames none;
  return ForCommandLine(error, error.source() == "command line" ? CommandLineFlags() : none);
}

InputError ForCommandLine(const InputError& error, const FlagNames& flags) {
  const auto flag = flags.find(error.key());
  const auto* request = dynamic_cast<const RequestError*>(&error);
  const std::optional<std::string> worded = request == nullptr ? std::nullopt : WordRemedy(*request);
  const bool renamed = flag != flags.end();
  if (!renamed && !worded) return error;
  // A plain InputError: worded once, it has no remedy left to word again.
  return InputError(error.source(), renamed ? flag->second : error.key(), error.value(),
                    worded ? *worded : error.expected(), error.line());
}

}  // namespace gesweep::cli
