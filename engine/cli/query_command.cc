// gesweep query: rows of an archive that satisfy a condition, or --describe: what it holds
// (docs/report.md, "gesweep query").
//   gesweep query ARCHIVE [--where EXPR] [--columns a,b,c] [--sort col [--descending]] [--limit n]
//                 [--format table|csv|json]
//   gesweep query ARCHIVE [--where EXPR] [--group-by a,b] --aggregate 'count,mean(c),quantile(c, 0.95)'
//                 [--sort OUT [--descending]] [--limit n] [--memory-mb N] [--max-groups N] [--format ...]
//   gesweep query ARCHIVE --describe [--format table|json]
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "engine/archive/archive_reader.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/common/errors.h"
#include "engine/query/aggregate.h"
#include "engine/query/query.h"
#include "engine/query/query_output.h"
#include "engine/query/run_columns.h"

namespace gesweep::cli {
namespace {

// An aggregate query's memory for exact medians and quantiles, and its most groups, unless given.
constexpr long long kDefaultMemoryMb = 256;
constexpr long long kDefaultMaxGroups = 1'000'000;

struct QueryFlags {
  std::string archive;
  std::string where;
  std::vector<std::string> columns;
  std::string sort;
  bool descending = false;
  long long limit = -1;
  QueryFormat format = QueryFormat::kAligned;
  bool describe = false;
  std::vector<std::string> group_by;
  std::vector<std::string> aggregates;
  std::optional<long long> memory_mb;   // none: kDefaultMemoryMb
  std::optional<long long> max_groups;  // none: kDefaultMaxGroups
  DescribedFlags described;

  /// The settings whose flag is their key's name (DescribedFlags, added by CommandWith); the others
  /// are added by hand (AddQueryFlags).
  template <class V>
  void Describe(V& v) {
    v(Field("columns", &columns)
          .Doc("Columns to show, comma-separated; wildcards such as 'phugoid/*' or '*' (default: index, "
               "design, status)"));
    v(Field("group_by", &group_by)
          .Doc("Columns whose equal values form a group, comma-separated (wildcards allowed); with "
               "--aggregate"));
    v(Field("descending", &descending).Doc("Sort largest first"));
    v(Field("describe", &describe).Doc("List the columns with units, run counts by status, provenance"));
    v(Field("format", &format).Doc("Output: an aligned table for a person, CSV or JSON for a program"));
  }
};

// The fields a row query and an aggregate query share, from the flags.
template <class Request>
Request RequestOf(const QueryFlags& flags) {
  Request request;
  request.where = flags.where;
  request.sort = flags.sort;
  request.descending = flags.descending;
  request.limit = flags.limit;
  return request;
}

// Root attributes too long for a listing: shown by their size.
bool LongText(const std::string& name) { return name == "study_text" || name == "aircraft_text"; }

std::string TypeText(const RunColumn& column) {
  if (column.kind == ColumnKind::kText) return "text";
  if (column.kind == ColumnKind::kUnsigned) return "uint64";
  if (!column.levels.empty()) return "level";
  return column.integer ? "integer" : "float64";
}

std::string Shape(const std::vector<std::int64_t>& shape) {
  std::string text;
  for (auto d : shape) text += (text.empty() ? "" : " x ") + std::to_string(d);
  return text.empty() ? "scalar" : text;
}

int Describe(const ArchiveReader& archive, const ColumnCatalog& catalog, QueryFormat format) {
  const StatusCounts counts = CountStatuses(archive);
  const std::vector<AttributeText> provenance = ReadAttributes(archive, "/");
  if (format == QueryFormat::kCsv) {
    throw InputError("command line", "--format", "csv", "expected table or json with --describe");
  }
  if (format == QueryFormat::kJson) {
    nlohmann::json columns = nlohmann::json::array(), others = nlohmann::json::array(), attributes;
    for (const auto& c : catalog.columns()) {
      nlohmann::json entry = {{"name", c.name},
                              {"path", c.path},
                              {"units", c.units},
                              {"type", TypeText(c)},
                              {"description", c.description}};
      if (!c.levels.empty()) entry["levels"] = c.levels;
      columns.push_back(entry);
    }
    for (const auto& o : catalog.others()) {
      others.push_back({{"path", o.path},
                        {"shape", o.shape},
                        {"units", o.units},
                        {"description", o.description},
                        {"not_a_column", o.why}});
    }
    for (const auto& a : provenance) attributes[a.name] = a.value;
    nlohmann::json out = {
        {"archive", archive.path().string()},
        {"runs", archive.run_count()},
        {"status", {{"ok", counts.ok}, {"failed", counts.failed}, {"pending", counts.pending}}},
        {"snapshot", archive.snapshot()},
        {"columns", columns},
        {"other_datasets", others},
        {"provenance", attributes}};
    std::cout << out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return 0;
  }
  std::cout << "# " << archive.path().string() << ": study " << archive.StringAttribute("study_name") << ", "
            << archive.run_count() << " runs: " << counts.ok << " ok, " << counts.failed << " failed, "
            << counts.pending << " pending\n";
  if (archive.snapshot()) {
    std::cout << "# snapshot: a sweep is writing this archive, or its writer stopped without closing it; "
                 "the counts are of the runs complete so far\n";
  }
  std::size_t name_width = 4, units_width = 5;
  for (const auto& c : catalog.columns()) {
    name_width = std::max(name_width, c.name.size());
    units_width = std::max(units_width, c.units.size());
  }
  std::cout << "\n# columns (query them by name; the full dataset path works too)\n";
  std::cout << std::left << std::setw(static_cast<int>(name_width)) << "name"
            << "  " << std::setw(static_cast<int>(units_width)) << "units"
            << "  " << std::setw(8) << "type"
            << "  description\n";
  for (const auto& c : catalog.columns()) {
    std::string description = c.description;
    if (!c.levels.empty()) {
      std::string levels;
      for (const auto& l : c.levels) levels += (levels.empty() ? "" : ", ") + l;
      description += " [levels: " + levels + "]";
    }
    if (c.name != c.path) description += " (" + c.path + ")";
    std::cout << std::setw(static_cast<int>(name_width)) << c.name << "  "
              << std::setw(static_cast<int>(units_width)) << (c.units.empty() ? "-" : c.units) << "  "
              << std::setw(8) << TypeText(c) << "  " << description << "\n";
  }
  if (!catalog.others().empty()) {
    std::cout << "\n# other datasets (not query columns)\n";
    for (const auto& o : catalog.others()) {
      std::cout << o.path << "  [" << Shape(o.shape) << "]  " << (o.units.empty() ? "-" : o.units) << "  "
                << o.why << (o.description.empty() ? "" : ": " + o.description) << "\n";
    }
  }
  std::cout << "\n# provenance (root attributes)\n";
  for (const auto& a : provenance) {
    if (LongText(a.name)) {
      std::cout << a.name << " = (" << a.value.size() << " characters of TOML)\n";
    } else {
      std::cout << a.name << " = " << a.value << "\n";
    }
  }
  std::cout << std::right;
  return 0;
}

int RunQueryCommand(const QueryFlags& flags) {
  const QueryFormat format = flags.format;
  if (flags.limit < -1) {
    throw InputError("command line", "--limit", std::to_string(flags.limit), "expected a count >= 0");
  }
  return GuardArchive([&] {
    const ArchiveReader archive = ArchiveReader::Open(flags.archive);
    const ColumnCatalog catalog = ColumnCatalog::Of(archive);
    const bool aggregating = !flags.group_by.empty() || !flags.aggregates.empty();
    if (flags.describe) {
      if (!flags.where.empty() || !flags.columns.empty() || !flags.sort.empty() || flags.limit >= 0 ||
          aggregating) {
        throw InputError("command line", "--describe", "",
                         "lists what the archive holds; it takes no --where, --columns, --sort, --limit, "
                         "--group-by or --aggregate");
      }
      return Describe(archive, catalog, format);
    }
    if (flags.descending && flags.sort.empty()) {
      throw InputError("command line", "--descending", "", "sorts by --sort; give --sort COLUMN");
    }
    if (!aggregating && (flags.memory_mb || flags.max_groups)) {
      throw InputError("command line", flags.memory_mb ? "--memory-mb" : "--max-groups", "",
                       "applies to --group-by/--aggregate only");
    }
    if (aggregating) {
      if (!flags.columns.empty()) {
        throw InputError("command line", "--columns", "",
                         "lists runs; with --group-by/--aggregate the output columns are the groups and "
                         "the statistics");
      }
      const long long memory_mb = flags.memory_mb.value_or(kDefaultMemoryMb);
      const long long max_groups = flags.max_groups.value_or(kDefaultMaxGroups);
      if (memory_mb < 1 || memory_mb > (std::int64_t{1} << 20)) {
        throw InputError("command line", "--memory-mb", std::to_string(memory_mb),
                         "expected megabytes, 1 to 1048576");
      }
      if (max_groups < 1) {
        throw InputError("command line", "--max-groups", std::to_string(max_groups), "expected a count >= 1");
      }
      auto request = RequestOf<AggregateRequest>(flags);
      request.group_by = flags.group_by;
      request.aggregates = flags.aggregates;
      request.memory_bytes = static_cast<std::int64_t>(memory_mb) << 20;
      request.max_groups = max_groups;
      const auto writer = MakeQueryWriter(format, std::cout, flags.archive);
      RunAggregateQuery(archive, catalog, request, *writer);
      return 0;
    }
    auto request = RequestOf<QueryRequest>(flags);
    request.columns = flags.columns;
    const auto writer = MakeQueryWriter(format, std::cout, flags.archive);
    RunQuery(archive, catalog, request, *writer);
    return 0;
  });
}

void AddQueryFlags(CLI::App& app, QueryFlags& flags) {
  AddArchiveArgument(app, flags.archive, "Archive (HDF5) written by gesweep run");
  app.add_option("--where", flags.where,
                 "Condition, e.g. 'height_m < 3 and stability_margin_per_s > 0', 'status == \"failed\"' "
                 "(docs/report.md)");
  app.add_option("--aggregate", flags.aggregates,
                 "Statistics per group: count, count(c), sum(c), min(c), max(c), mean(c), std(c[, 0]), "
                 "median(c), quantile(c, p); comma-separated, repeatable (default with --group-by: count)");
  app.add_option("--memory-mb", flags.memory_mb,
                 "Memory for exact medians and quantiles (default " + std::to_string(kDefaultMemoryMb) +
                     "); past it, more passes")
      ->check(ExactIntegerValidator("--memory-mb", "query.memory_mb",
                                    static_cast<double>(std::numeric_limits<long long>::max())));
  app.add_option("--max-groups", flags.max_groups,
                 "Refuse more groups than this (default " + std::to_string(kDefaultMaxGroups) + ")")
      ->check(ExactIntegerValidator("--max-groups", "max_groups",
                                    static_cast<double>(std::numeric_limits<long long>::max())));
  app.add_option("--sort", flags.sort,
                 "Column to sort by (missing values last); with --aggregate an output column");
  app.add_option("--limit", flags.limit,
                 "Show at most this many rows (with --sort: the best n); with --aggregate, groups")
      ->check(ExactIntegerValidator("--limit", "query.limit",
                                    static_cast<double>(std::numeric_limits<long long>::max())));
}

const CommandRegistrar kRegistrar{CommandWith<QueryFlags>(
    "query", "Select runs of an archive by a condition, with chosen columns, sorted; or --describe it",
    AddQueryFlags, RunQueryCommand)};

}  // namespace
}  // namespace gesweep::cli
