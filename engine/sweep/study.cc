#include "engine/sweep/study.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/common/notes.h"
#include "engine/common/toml_reader.h"
#include "engine/sweep/hashing.h"

namespace gesweep {
namespace {

// Bounds that keep a study within what one archive and one machine can sensibly hold; a design
// past them is almost certainly a typo (docs/sweep.md, "Refusing absurd designs").
constexpr std::int64_t kMaximumAxisPoints = 100'000'000;
constexpr std::int64_t kMaximumListRows = 100'000'000;
constexpr int kMaximumChunkRuns = 1 << 16;

std::string Quote(const std::string& text) { return "\"" + text + "\""; }

std::string FormatNumber(double value) { return ShortNumber(value); }

int NodeLine(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

// The id of a parameter's name or of an older name of it (RenamedParameters); an older name is
// accepted with a note naming where it was written (docs/sweep.md, "Renamed parameters").
std::optional<ParameterId> IdOfNameOrOlder(const std::string& name, const std::string& key, int line,
                                           const std::string& source) {
  std::string note;
  const auto id = FindParameterOrOlder(name, &note);
  if (!note.empty())
    SendNote(source + (line > 0 ? ":" + std::to_string(line) : "") + ": " + key + ": " + note);
  return id;
}

class StudyParser {
 public:
  StudyParser(const std::string& text, std::filesystem::path path)
      : path_(std::move(path)), source_(path_.string()), root_(ParseToml(text, source_)) {
    study_.path = source_;
    study_.text = text;
    study_.inputs.push_back({path_, "study file"});
  }

  Study Parse() {
    TomlSection root(root_, source_, "");
    root.RejectUnknownKeys({"format_version", "name", "description", "aircraft", "analyses", "output",
                            "parameters", "design", "subset"});
    // [subset] (a subset simulation of the study's landings, `gesweep risk`): read by engine/risk.
    if (root.Has("subset")) study_.subset_line = std::max(1, root.LineOf("subset"));
    const auto version = root.OptionalInteger("format_version");
    if (!version)
      root.Fail("format_version", "",
                "missing key, expected format_version = " + std::to_string(kStudyFormatVersion));
    if (*version != kStudyFormatVersion) {
      root.Fail("format_version", std::to_string(*version),
                "expected " + std::to_string(kStudyFormatVersion) + " (the study format this engine reads)");
    }
    study_.name = root.OptionalString("name").value_or(path_.stem().string());
    if (study_.name.empty()) root.Fail("name", "\"\"", "expected a non-empty name");
    study_.description = root.OptionalString("description").value_or("");

    ParseAnalysesNames(root);
    ParseAircraft(root);
    BuildAnalyses(root);
    ParseOutput(root);
    ParseParameters(root);
    ParseDesign(root);
    CrossCheck(root);
    Fingerprint();
    return std::move(study_);
  }

 private:
  // Pass 1: which analyses, so the aircraft requirement is known before their settings are read.
  void ParseAnalysesNames(const TomlSection& root) {
    const TomlSection analyses = root.Section("analyses");
    std::vector<std::string> known;
    for (const auto& entry : AnalysisRegistry()) known.emplace_back(entry.name);
    analyses.RejectUnknownKeys(known);
    for (const auto& entry : AnalysisRegistry()) {
      if (!analyses.Has(entry.name)) continue;
      const toml::node* node = analyses.table().get(entry.name);
      if (!node->is_table()) {
        analyses.Fail(entry.name, DescribeNode(*node),
                      "expected a table of settings, e.g. [analyses." + std::string(entry.name) + "] or " +
                          std::string(entry.name) + " = {}");
      }
      if (entry.factory == nullptr) {
        analyses.Fail(entry.name, "",
                      "analysis '" + std::string(entry.name) +
                          "' is not available in this build: " + std::string(entry.unavailable_reason));
      }
      requested_.push_back(&entry);
    }
    if (requested_.empty()) {
      std::string names;
      for (const auto& entry : AnalysisRegistry())
        names += (names.empty() ? "" : ", ") + std::string(entry.name);
      throw InputError(source_, "analyses", "{}", "expected at least one analysis (" + names + ")",
                       analyses.LineOf(""));
    }
  }

  void ParseAircraft(const TomlSection& root) {
    const auto aircraft = root.OptionalString("aircraft");
    if (!aircraft) return;
    if (aircraft->empty()) root.Fail("aircraft", "\"\"", "expected the path of an aircraft file");
    std::filesystem::path aircraft_path(*aircraft);
    if (aircraft_path.is_relative()) aircraft_path = path_.parent_path() / aircraft_path;
    std::error_code ec_study, ec_aircraft;
    const auto study_canonical = std::filesystem::weakly_canonical(path_, ec_study);
    const auto aircraft_canonical = std::filesystem::weakly_canonical(aircraft_path, ec_aircraft);
    if (!ec_study && !ec_aircraft && study_canonical == aircraft_canonical) {
      root.Fail("aircraft", Quote(*aircraft), "expected an aircraft file, not this study file itself");
    }
    study_.inputs.push_back({aircraft_path, "aircraft file"});
    try {
      study_.aircraft = LoadAircraftFile(aircraft_path);
    } catch (const InputError& e) {
      // Name the study key that led there, then the aircraft file's own complaint.
      if (e.source() == aircraft_path.string() && e.key().empty() && e.line() == 0) {
        root.Fail("aircraft", Quote(*aircraft), e.expected() + " (" + aircraft_path.string() + ")");
      }
      throw;
    }
  }

  void BuildAnalyses(const TomlSection& root) {
    const TomlSection analyses = root.Section("analyses");
    for (const AnalysisEntry* entry : requested_) {
      const TomlSection settings = analyses.Section(entry->name);
      if (entry->needs_model && !study_.aircraft) {
        root.Fail("aircraft", "",
                  "missing key: analysis '" + std::string(entry->name) +
                      "' needs an aircraft file, e.g. aircraft = \"aircraft/ance.toml\"");
      }
      std::unique_ptr<Analysis> analysis =
          entry->factory(settings, study_.aircraft ? &*study_.aircraft : nullptr);
      GESWEEP_DEMAND(analysis != nullptr && analysis->needs_model() == entry->needs_model);
      study_.analyses.push_back(std::move(analysis));
    }
  }

  void ParseOutput(const TomlSection& root) {
    const auto output = root.OptionalSection("output");
    if (!output) return;
    output->RejectUnknownKeys({"time_series", "output_dt_s", "chunk_runs", "compression_level",
                               "deflate_encoder", "max_archive_gb"});
    study_.storage.time_series = output->OptionalBool("time_series").value_or(false);
    if (const auto dt = output->OptionalLimitedNumber("output_dt_s", "output_dt_s"))
      study_.storage.output_dt_s = *dt;
    if (const auto chunk = output->OptionalInteger("chunk_runs")) {
      if (*chunk < 1 || *chunk > kMaximumChunkRuns || (*chunk & (*chunk - 1)) != 0) {
        output->Fail("chunk_runs", std::to_string(*chunk),
                     "expected a power of two from 1 to " + std::to_string(kMaximumChunkRuns));
      }
      study_.chunk_runs = static_cast<int>(*chunk);
    }
    if (const auto level = output->OptionalInteger("compression_level")) {
      if (*level < 0 || *level > 9)
        output->Fail("compression_level", std::to_string(*level), "expected 0 to 9");
      study_.compression_level = static_cast<int>(*level);
    }
    if (const auto encoder = output->OptionalString("deflate_encoder")) {
      const auto parsed = ParseEnum<DeflateEncoder>(*encoder);
      if (!parsed) {
        output->Fail("deflate_encoder", "\"" + *encoder + "\"",
                     "expected " + EnumChoices<DeflateEncoder>() +
                         " (the same zlib format, read by every reader; libdeflate is faster)");
      }
      study_.deflate_encoder = *parsed;
    }
    if (output->Has("max_archive_gb")) study_.max_archive_gb = output->PositiveNumber("max_archive_gb");
  }

  // Whether `id` takes whole numbers only (its limits-table entry is whole: the seed).
  static bool IsWhole(ParameterId id) {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(id)];
    return info.kind == ParameterKind::kReal && RequireInputLimit(info.limit).whole;
  }

  // A value of parameter `id` from a TOML node: a number for a real, true/false for a boolean, a
  // level name for a choice.
  double ParameterValue(ParameterId id, const toml::node& node, const std::string& key) const {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(id)];
    double value = 0;
    if (info.kind == ParameterKind::kReal && IsWhole(id)) {
      // A seed: a TOML integer, its digits checked exactly (a float such as 9007199254740993.0 has
      // been rounded by the TOML reader already, so none is taken).
      auto i = node.as_integer();
      if (!i) {
        throw InputError(
            source_, key, DescribeNode(node),
            "expected " + DescribeAllowedValues(id) + " written as an integer (no fraction or exponent)",
            NodeLine(node));
      }
      try {
        value = static_cast<double>(ParseExactInteger(std::to_string(i->get()), info.limit, source_, key));
      } catch (const InputError& error) {
        throw InputError(source_, key, DescribeNode(node), error.expected(), NodeLine(node));
      }
    } else if (info.kind == ParameterKind::kReal) {
      if (auto f = node.as_floating_point()) {
        value = f->get();
      } else if (auto i = node.as_integer()) {
        value = static_cast<double>(i->get());
      } else {
        throw InputError(source_, key, DescribeNode(node), "expected " + DescribeAllowedValues(id),
                         NodeLine(node));
      }
    } else if (info.kind == ParameterKind::kBoolean) {
      auto b = node.as_boolean();
      if (!b) throw InputError(source_, key, DescribeNode(node), "expected true or false", NodeLine(node));
      value = b->get() ? 1.0 : 0.0;
    } else {
      auto s = node.as_string();
      const auto level = s ? ParseParameterLevel(id, s->get()) : std::nullopt;
      if (!level)
        throw InputError(source_, key, DescribeNode(node), "expected " + DescribeAllowedValues(id),
                         NodeLine(node));
      value = *level;
    }
    const std::string problem = CheckParameterValue(id, value, study_.aircraft ? &*study_.aircraft : nullptr);
    if (!problem.empty()) throw InputError(source_, key, DescribeNode(node), problem, NodeLine(node));
    return value;
  }

  // The id of a parameter's name or of an older name of it (RenamedParameters, with a note).
  ParameterId ParameterIdOf(const std::string& name, const std::string& key, int line) const {
    const auto id = IdOfNameOrOlder(name, key, line, source_);
    if (!id) {
      const std::string near = NearestName(name, ParameterNames());
      throw InputError(source_, key, Quote(name),
                       near.empty() ? "unknown parameter (see schemas/study.schema.json for the list)"
                                    : "unknown parameter (did you mean '" + near + "'?)",
                       line);
    }
    return *id;
  }

  void ParseParameters(const TomlSection& root) {
    const auto parameters = root.OptionalSection("parameters");
    if (!parameters) return;
    // Dotted names (scale.CLh = 1.1) arrive as nested tables; flatten them.
    std::vector<std::pair<std::string, const toml::node*>> flat;
    auto flatten = [&](auto&& self, const toml::table& table, const std::string& prefix) -> void {
      for (const auto& [key, node] : table) {
        const std::string name =
            prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
        if (node.is_table() && !FindParameter(name)) {
          self(self, *node.as_table(), name);
        } else {
          flat.emplace_back(name, &node);
        }
      }
    };
    flatten(flatten, parameters->table(), "");
    for (const auto& [name, node] : flat) {
      const std::string key = "parameters." + name;
      const ParameterId id = ParameterIdOf(name, key, NodeLine(*node));
      if (fixed_lines_.count(id) != 0) {  // a name and an older name of it
        throw InputError(source_, key, DescribeNode(*node),
                         "expected one value of " + ParameterCatalog()[static_cast<std::size_t>(id)].name +
                             " (it is given on line " + std::to_string(fixed_lines_.at(id)) + " too)",
                         NodeLine(*node));
      }
      study_.fixed.push_back({id, ParameterValue(id, *node, key)});
      fixed_lines_[id] = NodeLine(*node);
    }
    std::sort(study_.fixed.begin(), study_.fixed.end(),
              [](const auto& a, const auto& b) { return a.id < b.id; });
  }

  std::int64_t PositiveCount(const TomlSection& design, const char* key, std::int64_t maximum) const {
    const auto value = design.OptionalInteger(key);
    if (!value) design.Fail(key, "", std::string("missing key, expected a whole number >= 1"));
    if (*value < 1 || *value > maximum) {
      design.Fail(key, std::to_string(*value),
                  "expected a whole number from 1 to " + std::to_string(maximum));
    }
    return *value;
  }

  std::uint64_t Seed(const TomlSection& design) const {
    const auto seed = design.OptionalInteger("seed");
    if (!seed)
      design.Fail("seed", "",
                  "missing key, expected a seed (a whole number >= 0) so the design is reproducible");
    // The TOML integer's own digits, checked exactly against the table's seed entry (as --seed).
    try {
      return ParseExactInteger(std::to_string(*seed), "seed", source_, "seed");
    } catch (const InputError& error) {
      design.Fail("seed", error.value(), error.expected());
    }
  }

  // The [[design.parameter]] tables of `design`: each a table of the keys `allowed` naming a catalogue
  // parameter not named before (`per` and `duplicate` word those two errors for the design's kind).
  // `read(entry, name, parameter)` reads the rest of the entry; the parameter is then appended to the
  // design.
  template <typename Read>
  void ReadDesignParameters(const TomlSection& design, const std::string& per, const std::string& duplicate,
                            const std::vector<std::string>& allowed, const Read& read) {
    const toml::node* node = design.table().get("parameter");
    if (node == nullptr) {
      design.Fail("parameter", "", "missing [[design.parameter]] entries (" + per + ")");
    }
    const toml::array* array = node->as_array();
    if (array == nullptr || array->empty()) {
      design.Fail("parameter", DescribeNode(*node), "expected one or more [[design.parameter]] tables");
    }
    std::set<ParameterId> seen;
    for (std::size_t i = 0; i < array->size(); ++i) {
      const std::string prefix = "design.parameter[" + std::to_string(i) + "]";
      const toml::table* table = array->get(i)->as_table();
      if (table == nullptr) {
        throw InputError(source_, prefix, DescribeNode(*array->get(i)), "expected a table",
                         NodeLine(*array->get(i)));
      }
      const TomlSection entry(*table, source_, prefix);
      entry.RejectUnknownKeys(allowed);
      const std::string name = entry.String("name");
      DesignParameter parameter;
      parameter.id = ParameterIdOf(name, entry.KeyOf("name"), entry.LineOf("name"));
      if (!seen.insert(parameter.id).second) {
        entry.Fail("name", Quote(name), "expected each parameter once in the design (" + duplicate + ")");
      }
      swept_lines_[parameter.id] = entry.LineOf("name");
      read(entry, name, parameter);
      study_.design.parameters.push_back(std::move(parameter));
    }
  }

  // [[design.parameter]] entries: name plus, for a grid, values/linspace/logspace; for a sampled
  // design, uniform/loguniform bounds.
  void ParseDesignParameters(const TomlSection& design, bool grid) {
    const std::vector<std::string> allowed =
        grid ? std::vector<std::string>{"name", "values", "linspace", "logspace"}
             : std::vector<std::string>{"name", "uniform", "loguniform"};
    ReadDesignParameters(
        design, "one per swept parameter", "it is a duplicate axis", allowed,
        [&](const TomlSection& entry, const std::string& name, DesignParameter& parameter) {
          const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(parameter.id)];
          if (grid) {
            ParseGridAxis(entry, parameter);
          } else {
            if (info.kind != ParameterKind::kReal) {
              entry.Fail("name", Quote(name),
                         "expected a real-valued parameter: a " + std::string(ToString(study_.design.kind)) +
                             " design samples numbers; sweep " + name + " in a grid or list design");
            }
            ParseBounds(entry, parameter);
          }
        });
  }

  // The entry's `values = [...]` (non-empty), each checked against the parameter, into its values.
  void ReadValues(const TomlSection& entry, DesignParameter& parameter) const {
    const toml::array* array = entry.table().get("values")->as_array();
    if (array == nullptr || array->empty()) {
      entry.Fail("values", DescribeNode(*entry.table().get("values")),
                 "expected a non-empty array of values");
    }
    for (std::size_t k = 0; k < array->size(); ++k) {
      parameter.values.push_back(ParameterValue(parameter.id, *array->get(k),
                                                entry.KeyOf("values") + "[" + std::to_string(k) + "]"));
    }
  }

  // The entry's `linspace` or `logspace = [start, stop, n]` (a real parameter's), its n values
  // into the parameter's values: evenly or geometrically spaced, a seed's whole and computed in
  // integers, the ends checked against the parameter.
  void ReadSpacedValues(const TomlSection& entry, DesignParameter& parameter) const {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(parameter.id)];
    const char* key = entry.Has("linspace") ? "linspace" : "logspace";
    if (info.kind != ParameterKind::kReal) {
      entry.Fail(
          key, "",
          "expected values = [...] for " + info.name + " (" + DescribeAllowedValues(parameter.id) + ")");
    }
    const std::vector<double> spec = entry.NumberArray(key);
    if (spec.size() != 3 || spec[2] < 1 || spec[2] != std::floor(spec[2]) ||
        spec[2] > static_cast<double>(kMaximumAxisPoints)) {
      entry.Fail(key, "[...]",
                 "expected [start, stop, n] with a whole n from 1 to " + std::to_string(kMaximumAxisPoints));
    }
    const auto n = static_cast<std::int64_t>(spec[2]);
    parameter.values.reserve(static_cast<std::size_t>(n));
    const bool log = std::string(key) == "logspace";
    if (IsWhole(parameter.id)) {
      // A seed axis: whole ends and a whole spacing, the values start + k * spacing computed in
      // integers (start + t * (stop - start) in doubles gives 0.9999999999999999 for 1 of [0, 1999]).
      for (double end : {spec[0], spec[1]}) {
        const std::string problem =
            CheckParameterValue(parameter.id, end, study_.aircraft ? &*study_.aircraft : nullptr);
        if (!problem.empty()) entry.Fail(key, FormatNumber(end), problem);
      }
      const double span = spec[1] - spec[0];
      if (log || (n > 1 && std::fmod(span, static_cast<double>(n - 1)) != 0.0)) {
        entry.Fail(
            key,
            "[" + FormatNumber(spec[0]) + ", " + FormatNumber(spec[1]) + ", " + FormatNumber(spec[2]) + "]",
            "expected whole values for " + info.name +
                ": linspace = [start, stop, n] with stop - start a multiple of n - 1 (or values = [...])");
      }
      const auto start = static_cast<std::int64_t>(spec[0]);
      const std::int64_t spacing = n > 1 ? static_cast<std::int64_t>(span) / (n - 1) : 0;
      for (std::int64_t k = 0; k < n; ++k)
        parameter.values.push_back(static_cast<double>(start + k * spacing));
    }
    if (log && !(spec[0] > 0 && spec[1] > 0)) {
      entry.Fail(key, "[" + FormatNumber(spec[0]) + ", " + FormatNumber(spec[1]) + ", ...]",
                 "expected start and stop > 0 (logspace spaces values geometrically between them)");
    }
    for (std::int64_t k = 0; k < n && !IsWhole(parameter.id); ++k) {
      const double t = n == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(n - 1);
      double value = log ? std::exp(std::log(spec[0]) + t * (std::log(spec[1]) - std::log(spec[0])))
                         : spec[0] + t * (spec[1] - spec[0]);
      if (k == n - 1 && n > 1) value = spec[1];  // land exactly on the end point
      parameter.values.push_back(value);
    }
    for (double value : {spec[0], spec[1]}) {
      const std::string problem =
          CheckParameterValue(parameter.id, value, study_.aircraft ? &*study_.aircraft : nullptr);
      if (!problem.empty()) entry.Fail(key, FormatNumber(value), problem);
    }
  }

  // The axis's values are distinct (a repeated value repeats runs).
  static void CheckDistinct(const TomlSection& entry, const DesignParameter& parameter) {
    // Distinct values: a spaced axis is monotone, so neighbours suffice (no memory per value);
    // explicit values are few, and sorted in a copy.
    bool distinct = true;
    if (entry.Has("values")) {
      std::vector<double> sorted = parameter.values;
      std::sort(sorted.begin(), sorted.end());
      distinct = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
    } else {
      for (std::size_t k = 1; k < parameter.values.size() && distinct; ++k) {
        distinct = parameter.values[k] != parameter.values[k - 1];
      }
    }
    if (!distinct) {
      entry.Fail(entry.Has("values") ? "values" : (entry.Has("linspace") ? "linspace" : "logspace"), "[...]",
                 "expected distinct values (a repeated value repeats runs)");
    }
  }

  void ParseGridAxis(const TomlSection& entry, DesignParameter& parameter) {
    const int given = entry.Has("values") + entry.Has("linspace") + entry.Has("logspace");
    if (given != 1) {
      entry.Fail("name", "",
                 "expected exactly one of values = [...], linspace = [start, stop, n] or "
                 "logspace = [start, stop, n]");
    }
    if (entry.Has("values")) {
      ReadValues(entry, parameter);
    } else {
      ReadSpacedValues(entry, parameter);
    }
    CheckDistinct(entry, parameter);
  }

  // [[design.parameter]] entries of a monte_carlo design: name and exactly one distribution.
  void ParseMonteCarloParameters(const TomlSection& design) {
    static const std::vector<std::string> kContinuous = {"normal", "truncated_normal", "uniform",
                                                         "loguniform", "lognormal"};
    ReadDesignParameters(
        design, "one per sampled parameter", "it is a duplicate",
        {"name", "normal", "truncated_normal", "uniform", "loguniform", "lognormal", "values", "weights"},
        [&](const TomlSection& entry, const std::string& name, DesignParameter& parameter) {
          int given = entry.Has("values");
          std::string key = "values";
          for (const auto& distribution : kContinuous) {
            if (entry.Has(distribution)) {
              ++given;
              key = distribution;
            }
          }
          if (given != 1) {
            entry.Fail(
                "name", Quote(name),
                "expected exactly one distribution: normal = [mean, sigma], truncated_normal = [mean, "
                "sigma, lower, upper], uniform = [lower, upper], loguniform = [lower, upper], lognormal "
                "= [mean of log, sigma of log], or values = [...] with optional weights = [...]");
          }
          if (entry.Has("weights") && key != "values") {
            entry.Fail("weights", "[...]",
                       "expected weights only beside values = [...] (a discrete distribution)");
          }
          const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(parameter.id)];
          const Aircraft* aircraft = study_.aircraft ? &*study_.aircraft : nullptr;
          if (key == "values") {
            ParseDiscrete(entry, parameter);
          } else {
            if (info.kind != ParameterKind::kReal || IsWhole(parameter.id)) {
              entry.Fail(key, "[...]",
                         "expected values = [...] (with optional weights = [...]) for " + name +
                             ": a continuous distribution needs a real-valued parameter (" +
                             DescribeAllowedValues(parameter.id) + ")");
            }
            if (key == "uniform" || key == "loguniform") {
              ParseBounds(entry, parameter);  // checks both bounds against the parameter
              return;
            }
            ParseNormalKind(entry, key, parameter);
            // The reach: the smallest and largest value any draw can take, checked against the parameter.
            parameter.lower = MonteCarloValue(parameter, kMonteCarloUnitLow);
            parameter.upper = MonteCarloValue(parameter, kMonteCarloUnitHigh);
            for (double value : {parameter.lower, parameter.upper}) {
              const std::string problem = CheckParameterValue(parameter.id, value, aircraft);
              if (!problem.empty()) {
                std::string expected =
                    "the distribution reaches " + FormatNumber(value) +
                    " (its value at probability 2^-53 from an end, the furthest a draw can go), and ";
                expected.append(name).append(": ").append(problem);
                if (key == "normal" || key == "lognormal")
                  expected += "; truncate it (truncated_normal) or narrow it";
                entry.Fail(key, "[...]", std::move(expected));
              }
            }
          }
        });
  }

  void ParseNormalKind(const TomlSection& entry, const std::string& key, DesignParameter& parameter) {
    const std::vector<double> numbers = entry.NumberArray(key);
    const bool truncated = key == "truncated_normal";
    const std::size_t count = truncated ? 4 : 2;
    const std::string form = key == "lognormal" ? "[mean of log, sigma of log]"
                             : truncated        ? "[mean, sigma, lower, upper]"
                                                : "[mean, sigma]";
    if (numbers.size() != count) entry.Fail(key, "[...]", "expected " + form);
    if (!(numbers[1] > 0)) entry.Fail(key, FormatNumber(numbers[1]), "expected sigma > 0 in " + form);
    parameter.mean = numbers[0];
    parameter.sigma = numbers[1];
    if (key == "normal") {
      parameter.distribution = Distribution::kNormal;
    } else if (key == "lognormal") {
      parameter.distribution = Distribution::kLogNormal;
      // exp of the reach must stay finite: |mean| + 8.3 sigma below log(DBL_MAX) ≈ 709.
      if (std::abs(numbers[0]) + 9 * numbers[1] > 700) {
        entry.Fail(key, "[...]", "expected |mean of log| + 9 sigma of log <= 700 (exp overflows beyond)");
      }
    } else {
      parameter.distribution = Distribution::kTruncatedNormal;
      if (!(numbers[2] < numbers[3])) {
        entry.Fail(key, "[" + FormatNumber(numbers[2]) + ", " + FormatNumber(numbers[3]) + "]",
                   "expected lower < upper in " + form);
      }
      parameter.truncate_lower = numbers[2];
      parameter.truncate_upper = numbers[3];
      if (!(TruncatedNormalMass(parameter) > 0)) {
        entry.Fail(key, "[...]",
                   "the interval [lower, upper] holds no probability of the normal (it lies about 38 sigma "
                   "or more from the mean); move it or widen sigma");
      }
    }
  }

  void ParseDiscrete(const TomlSection& entry, DesignParameter& parameter) {
    parameter.distribution = Distribution::kDiscrete;
    ReadValues(entry, parameter);
    std::vector<double> sorted = parameter.values;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      entry.Fail("values", "[...]", "expected distinct values (give a value's weight once, in weights)");
    }
    if (entry.Has("weights")) {
      parameter.weights = entry.NumberArray("weights");
      if (parameter.weights.size() != parameter.values.size()) {
        entry.Fail("weights", "[...]",
                   "expected " + std::to_string(parameter.values.size()) + " weights (one per value)");
      }
      double total = 0;
      for (double w : parameter.weights) {
        if (!(w > 0) || !std::isfinite(w)) {
          entry.Fail("weights", FormatNumber(w), "expected every weight finite and > 0");
        }
        total += w;
      }
      if (!std::isfinite(total)) entry.Fail("weights", "[...]", "expected weights whose sum is finite");
    } else {
      parameter.weights.assign(parameter.values.size(), 1.0);
    }
    parameter.lower = sorted.front();
    parameter.upper = sorted.back();
  }

  void ParseBounds(const TomlSection& entry, DesignParameter& parameter) {
    const int given = entry.Has("uniform") + entry.Has("loguniform");
    if (given != 1)
      entry.Fail("name", "",
                 "expected exactly one of uniform = [lower, upper] or loguniform = [lower, upper]");
    const char* key = entry.Has("uniform") ? "uniform" : "loguniform";
    if (IsWhole(parameter.id)) {
      entry.Fail(key, "[...]",
                 "a range is sampled with fractions, but " +
                     ParameterCatalog()[static_cast<std::size_t>(parameter.id)].name + " takes " +
                     DescribeAllowedValues(parameter.id) +
                     ": give it in [parameters], a grid or a list design");
    }
    parameter.distribution = entry.Has("uniform") ? Distribution::kUniform : Distribution::kLogUniform;
    const std::vector<double> bounds = entry.NumberArray(key);
    if (bounds.size() != 2 || !(bounds[0] < bounds[1])) {
      entry.Fail(key, "[...]", "expected [lower, upper] with lower < upper");
    }
    if (parameter.distribution == Distribution::kLogUniform && !(bounds[0] > 0)) {
      entry.Fail(key, FormatNumber(bounds[0]), "expected lower > 0 for a loguniform distribution");
    }
    for (double value : bounds) {
      const std::string problem =
          CheckParameterValue(parameter.id, value, study_.aircraft ? &*study_.aircraft : nullptr);
      if (!problem.empty()) entry.Fail(key, FormatNumber(value), problem);
    }
    parameter.lower = bounds[0];
    parameter.upper = bounds[1];
  }

  void ParseList(const TomlSection& design) {
    design.RejectUnknownKeys({"kind", "columns", "rows", "csv"});
    if (design.Has("rows") == design.Has("csv")) {
      design.Fail("rows", "",
                  "expected exactly one of rows = [[...], ...] (with columns = [...]) or csv = \"file.csv\"");
    }
    DesignSpec& spec = study_.design;
    if (design.Has("rows")) {
      const toml::node* columns_node = design.table().get("columns");
      if (columns_node == nullptr || !columns_node->is_array() || columns_node->as_array()->empty()) {
        design.Fail("columns", "", "expected columns = [\"parameter\", ...] naming the values of each row");
      }
      std::vector<std::string> names;
      const toml::array& columns = *columns_node->as_array();
      for (std::size_t i = 0; i < columns.size(); ++i) {
        auto s = columns.get(i)->as_string();
        if (!s) {
          throw InputError(source_, "design.columns[" + std::to_string(i) + "]",
                           DescribeNode(*columns.get(i)), "expected a parameter name",
                           NodeLine(*columns.get(i)));
        }
        names.push_back(s->get());
      }
      AddListColumns(
          names, [&](std::size_t i) { return "design.columns[" + std::to_string(i) + "]"; },
          design.LineOf("columns"));
      const toml::array* rows = design.table().get("rows")->as_array();
      if (rows == nullptr || rows->empty()) design.Fail("rows", "", "expected a non-empty array of rows");
      if (static_cast<std::int64_t>(rows->size()) > kMaximumListRows)
        design.Fail("rows", "", "too many rows");
      for (std::size_t r = 0; r < rows->size(); ++r) {
        const toml::array* row = rows->get(r)->as_array();
        const std::string key = "design.rows[" + std::to_string(r) + "]";
        if (row == nullptr || row->size() != names.size()) {
          throw InputError(source_, key, DescribeNode(*rows->get(r)),
                           "expected a row of " + std::to_string(names.size()) + " values (one per column)",
                           NodeLine(*rows->get(r)));
        }
        for (std::size_t c = 0; c < row->size(); ++c) {
          spec.list_values.push_back(
              ParameterValue(spec.parameters[c].id, *row->get(c), key + "[" + std::to_string(c) + "]"));
        }
      }
      spec.list_rows = static_cast<std::int64_t>(rows->size());
    } else {
      if (design.Has("columns"))
        design.Fail("columns", "", "not used with csv: the CSV header names the columns");
      ReadCsv(design);
    }
  }

  template <typename KeyOf>
  void AddListColumns(const std::vector<std::string>& names, KeyOf key_of, int line) {
    std::set<ParameterId> seen;
    for (std::size_t i = 0; i < names.size(); ++i) {
      DesignParameter parameter;
      parameter.id = ParameterIdOf(names[i], key_of(i), line);
      if (!seen.insert(parameter.id).second) {
        throw InputError(source_, key_of(i), Quote(names[i]),
                         "expected each parameter once (duplicate column)", line);
      }
      swept_lines_[parameter.id] = line;
      study_.design.parameters.push_back(parameter);
    }
  }

  static std::string Trim(const std::string& text) {
    const auto begin = text.find_first_not_of(" \t\r");
    if (begin == std::string::npos) return "";
    const auto end = text.find_last_not_of(" \t\r");
    return text.substr(begin, end - begin + 1);
  }

  static std::vector<std::string> SplitCsv(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ',')) cells.push_back(Trim(cell));
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
  }

  // The CSV's header `cells`: a known parameter per column, each once, appended to the design's
  // parameters. Throws InputError.
  void ReadCsvHeader(const TomlSection& design, const std::vector<std::string>& cells,
                     const std::string& csv_source, int line_number) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (cells[i].empty())
        throw InputError(csv_source, "header", "", "expected a parameter name in every column", line_number);
    }
    std::vector<std::string> names = cells;
    std::set<ParameterId> seen;
    for (std::size_t i = 0; i < names.size(); ++i) {
      const auto id = IdOfNameOrOlder(names[i], "header", line_number, csv_source);
      if (!id) {
        const std::string near = NearestName(names[i], ParameterNames());
        throw InputError(
            csv_source, "header", Quote(names[i]),
            near.empty() ? "unknown parameter" : "unknown parameter (did you mean '" + near + "'?)",
            line_number);
      }
      if (!seen.insert(*id).second)
        throw InputError(csv_source, "header", Quote(names[i]), "duplicate column", line_number);
      DesignParameter parameter;
      parameter.id = *id;
      swept_lines_[*id] = design.LineOf("csv");
      study_.design.parameters.push_back(parameter);
    }
  }

  // A CSV cell's value for parameter `id` of column `column`: a seed's digits exactly, a real number,
  // or a level, checked against the parameter. Throws InputError.
  double CsvCellValue(const std::string& cell, ParameterId id, const std::string& column,
                      const std::string& csv_source, int line_number) const {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(id)];
    double value = 0;
    bool parsed = false;
    if (IsWhole(id)) {
      // A seed: its digits, exactly (strtod would round 9007199254740993 to 2^53).
      try {
        value = static_cast<double>(ParseExactInteger(cell, info.limit, csv_source, column));
      } catch (const InputError& error) {
        throw InputError(csv_source, column, Quote(cell), error.expected(), line_number);
      }
      parsed = true;
    } else if (info.kind == ParameterKind::kReal) {
      const std::string magnitude = MagnitudeProblem(cell);
      if (!magnitude.empty()) {
        throw InputError(csv_source, column, Quote(cell), "the number " + magnitude, line_number);
      }
      char* end = nullptr;
      value = std::strtod(cell.c_str(), &end);
      parsed = !cell.empty() && end == cell.c_str() + cell.size();
    } else {
      const auto level = ParseParameterLevel(id, cell);
      parsed = level.has_value();
      if (parsed) value = *level;
    }
    std::string problem = parsed
                              ? CheckParameterValue(id, value, study_.aircraft ? &*study_.aircraft : nullptr)
                              : "expected " + DescribeAllowedValues(id);
    if (!problem.empty()) throw InputError(csv_source, column, Quote(cell), problem, line_number);
    return value;
  }

  void ReadCsv(const TomlSection& design) {
    const std::string csv = design.String("csv");
    std::filesystem::path csv_path(csv);
    if (csv_path.is_relative()) csv_path = path_.parent_path() / csv_path;
    study_.inputs.push_back({csv_path, "design CSV file"});
    const std::string text = ReadTextFile(csv_path, "design CSV file");
    csv_text_ = text;
    const std::string csv_source = csv_path.string();
    study_.design.list_csv = csv_source;
    std::stringstream stream(text);
    std::string line;
    int line_number = 0;
    std::vector<std::string> header;
    DesignSpec& spec = study_.design;
    while (std::getline(stream, line)) {
      ++line_number;
      const std::string trimmed = Trim(line);
      if (trimmed.empty() || trimmed[0] == '#') continue;
      const std::vector<std::string> cells = SplitCsv(trimmed);
      if (header.empty()) {
        header = cells;
        ReadCsvHeader(design, header, csv_source, line_number);
        continue;
      }
      if (cells.size() != header.size()) {
        throw InputError(
            csv_source, "row", trimmed,
            "expected " + std::to_string(header.size()) + " comma-separated values (one per header column)",
            line_number);
      }
      for (std::size_t c = 0; c < cells.size(); ++c) {
        spec.list_values.push_back(
            CsvCellValue(cells[c], spec.parameters[c].id, header[c], csv_source, line_number));
      }
      ++spec.list_rows;
      if (spec.list_rows > kMaximumListRows)
        throw InputError(csv_source, "", "", "too many rows", line_number);
    }
    if (header.empty())
      throw InputError(csv_source, "", "", "expected a header line naming the parameters", 0);
    if (spec.list_rows == 0)
      throw InputError(csv_source, "", "", "expected at least one row after the header", line_number);
  }

  void ParseDesign(const TomlSection& root) {
    const auto design = root.OptionalSection("design");
    DesignSpec& spec = study_.design;
    if (!design) {
      spec.kind = DesignKind::kSingle;
      return;
    }
    study_.design_line = root.LineOf("design");
    const std::string kind = design->String("kind");
    const std::vector<std::string> kinds = {"grid", "list", "lhs", "sobol", "morris", "monte_carlo"};
    if (kind == "grid") {
      spec.kind = DesignKind::kGrid;
      design->RejectUnknownKeys({"kind", "parameter"});
      ParseDesignParameters(*design, /*grid=*/true);
    } else if (kind == "list") {
      spec.kind = DesignKind::kList;
      ParseList(*design);
    } else if (kind == "lhs") {
      spec.kind = DesignKind::kLhs;
      design->RejectUnknownKeys({"kind", "samples", "seed", "parameter"});
      spec.samples = PositiveCount(*design, "samples", kMaximumListRows);
      spec.seed = Seed(*design);
      ParseDesignParameters(*design, /*grid=*/false);
    } else if (kind == "sobol") {
      spec.kind = DesignKind::kSobol;
      design->RejectUnknownKeys({"kind", "base_samples", "second_order", "parameter"});
      spec.base_samples = PositiveCount(*design, "base_samples", std::int64_t{1} << 40);
      spec.second_order = design->OptionalBool("second_order").value_or(false);
      ParseDesignParameters(*design, /*grid=*/false);
      if (static_cast<int>(spec.parameters.size()) > kMaximumSobolParameters) {
        design->Fail("parameter", std::to_string(spec.parameters.size()) + " parameters",
                     "expected at most " + std::to_string(kMaximumSobolParameters));
      }
    } else if (kind == "morris") {
      spec.kind = DesignKind::kMorris;
      design->RejectUnknownKeys({"kind", "trajectories", "levels", "seed", "parameter"});
      spec.trajectories = PositiveCount(*design, "trajectories", kMaximumListRows);
      const auto levels = design->OptionalInteger("levels");
      if (!levels)
        design->Fail("levels", "", "missing key, expected an even number of levels p >= 2 (e.g. 4)");
      if (*levels < 2 || *levels % 2 != 0 || *levels > kMaximumMorrisLevels) {
        design->Fail("levels", std::to_string(*levels),
                     "expected an even number of levels from 2 to " + std::to_string(kMaximumMorrisLevels));
      }
      spec.levels = static_cast<int>(*levels);
      spec.seed = Seed(*design);
      ParseDesignParameters(*design, /*grid=*/false);
    } else if (kind == "monte_carlo") {
      spec.kind = DesignKind::kMonteCarlo;
      design->RejectUnknownKeys({"kind", "samples", "seed", "parameter"});
      spec.samples = PositiveCount(*design, "samples", kMaximumListRows);
      spec.seed = Seed(*design);
      ParseMonteCarloParameters(*design);
    } else {
      const std::string near = NearestName(kind, kinds);
      design->Fail("kind", Quote(kind),
                   "expected grid, list, lhs, sobol, morris or monte_carlo" +
                       (near.empty() ? "" : " (did you mean '" + near + "'?)"));
    }
    if (CountRuns(spec) < 0) {
      design->Fail("kind", Quote(kind), "the design has more than 2^62 runs; refusing it");
    }
  }

  void CrossCheck(const TomlSection& root) {
    // Which parameters the chosen analyses read.
    std::set<ParameterId> used;
    bool model = false;
    for (const auto& analysis : study_.analyses) {
      for (ParameterId id : analysis->parameters_used()) used.insert(id);
      model = model || analysis->needs_model();
    }
    if (model) {
      for (ParameterId id = 0; id < ParameterCount(); ++id) {
        if (ParameterCatalog()[static_cast<std::size_t>(id)].group == ParameterGroup::kModel) used.insert(id);
      }
    }
    auto analyses_using = [&](ParameterId id) {
      const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(id)];
      switch (info.group) {
        case ParameterGroup::kFlight:
          return std::string("the analyses that fly a condition (modes, open_loop, landing)");
        case ParameterGroup::kModel:
          return std::string("every analysis with a model");
        case ParameterGroup::kOpenLoop:
          return std::string("open_loop");
        case ParameterGroup::kLanding:
          return std::string("landing");
        case ParameterGroup::kVerification:
          return std::string("the verification models (ishigami, linear)");
      }
      return std::string("?");
    };
    std::string analysis_names;
    for (const auto& analysis : study_.analyses) {
      analysis_names += (analysis_names.empty() ? "" : ", ") + std::string(analysis->name());
    }
    for (const auto& fixed : study_.fixed) {
      if (!used.count(fixed.id)) {
        const std::string& name = ParameterCatalog()[static_cast<std::size_t>(fixed.id)].name;
        throw InputError(source_, "parameters." + name, FormatParameterValue(fixed.id, fixed.value),
                         "no analysis of this study (" + analysis_names + ") reads it; it is read by " +
                             analyses_using(fixed.id),
                         fixed_lines_[fixed.id]);
      }
    }
    for (const auto& parameter : study_.design.parameters) {
      const std::string& name = ParameterCatalog()[static_cast<std::size_t>(parameter.id)].name;
      if (!used.count(parameter.id)) {
        throw InputError(source_, "design", Quote(name),
                         "sweeping it changes nothing: no analysis of this study (" + analysis_names +
                             ") reads it; it is read by " + analyses_using(parameter.id),
                         swept_lines_[parameter.id]);
      }
      if (fixed_lines_.count(parameter.id)) {
        throw InputError(source_, "parameters." + name, "",
                         "is both fixed in [parameters] and swept in [design]; keep one",
                         fixed_lines_[parameter.id]);
      }
    }
    // Every parameter an analysis reads needs a value: a default, a fixed value or a design column.
    for (const auto& analysis : study_.analyses) {
      for (ParameterId id : analysis->parameters_used()) {
        const bool given = fixed_lines_.count(id) || swept_lines_.count(id) ||
                           DefaultValue(id, study_.aircraft ? &*study_.aircraft : nullptr).has_value();
        if (!given) {
          const std::string& name = ParameterCatalog()[static_cast<std::size_t>(id)].name;
          throw InputError(source_, "parameters." + name, "",
                           "missing: analysis '" + std::string(analysis->name()) + "' needs " + name +
                               "; fix it in [parameters] or sweep it in [design] (" +
                               DescribeAllowedValues(id) + ")",
                           root.LineOf("parameters"));
        }
      }
    }
  }

  void Fingerprint() {
    // The parsed tables, re-serialised: comments and layout do not change the fingerprint.
    std::ostringstream canonical;
    canonical << root_;
    std::uint64_t hash = Fnv1a64(canonical.str());
    if (study_.aircraft) {
      std::ostringstream aircraft;
      aircraft << ParseToml(study_.aircraft->source_text, study_.aircraft->source_path);
      hash = Fnv1a64(aircraft.str(), Fnv1a64(std::string_view("\naircraft\n"), hash));
    }
    if (!csv_text_.empty()) hash = Fnv1a64(csv_text_, Fnv1a64(std::string_view("\ncsv\n"), hash));
    study_.fingerprint = hash;
  }

  std::filesystem::path path_;
  std::string source_;
  toml::table root_;
  Study study_;
  std::vector<const AnalysisEntry*> requested_;
  std::map<ParameterId, int> fixed_lines_;
  std::map<ParameterId, int> swept_lines_;
  std::string csv_text_;
};

}  // namespace

bool Study::needs_model() const {
  return std::any_of(analyses.begin(), analyses.end(), [](const auto& a) { return a->needs_model(); });
}

Study LoadStudy(const std::filesystem::path& path) {
  const std::string text = ReadTextFile(path, "study file");
  return ParseStudy(text, path);
}

Study ParseStudy(const std::string& text, const std::filesystem::path& path) {
  StudyParser parser(text, path);
  return parser.Parse();
}

}  // namespace gesweep
