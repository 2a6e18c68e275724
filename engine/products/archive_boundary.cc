#include "engine/products/archive_boundary.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/product_fields.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/modal/modal_analysis.h"
#include "engine/products/run_model.h"
#include "engine/query/run_columns.h"

namespace gesweep {
namespace {

constexpr const char* kMarginPath = "results/modes/stability_margin_per_s";
constexpr const char* kHeightPath = "design/height_m";
constexpr std::int64_t kChunkRows = 1 << 16;
// Samples per table segment inside a grid bracket, for BoundaryMethod::kSampled only (the default
// Hurwitz finder enumerates every crossing in the bracket; it keeps the highest).
constexpr int kRefineSamplesPerSegment = 8;
// The rebuilt model must give the archived σ at the bracket's ends. The same engine gives the same
// bits; this slack only absorbs a different compiler's rounding, not a different model.
constexpr double kMarginRelativeAgreement = 1e-8;
constexpr double kMarginAbsoluteAgreement = 1e-12;

struct Sample {
  double height_m;
  double margin_per_s;
  std::uint32_t group;
};

std::string Metres(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value << " m";
  return out.str();
}

std::string Number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// The boundary's key axes (every swept parameter but height_m): those of `by` first, in its order,
// then the others in design order. Throws for a `by` that is height_m or not swept.
std::vector<int> KeyColumns(const ColumnCatalog& catalog, int height_column,
                            const std::vector<std::string>& by) {
  std::vector<int> key_columns;
  std::vector<std::string> swept;
  for (int c : catalog.design_columns()) {
    if (c != height_column) swept.push_back(catalog.column(c).name);
  }
  for (const std::string& name : by) {
    const auto c = catalog.FindPath(archive::DesignPath(name));
    if (c == height_column) {
      throw RequestError("command line", "by", name, "the boundary is located along height_m",
                         "by_other_parameters");
    }
    if (!c || std::find(catalog.design_columns().begin(), catalog.design_columns().end(), *c) ==
                  catalog.design_columns().end()) {
      std::string list;
      for (const auto& s : swept) list += (list.empty() ? "" : ", ") + s;
      throw InputError(
          "command line", "by", name,
          "expected a parameter the design sweeps besides height_m" +
              (list.empty() ? std::string(" (it sweeps none: one boundary)") : " (" + list + ")"));
    }
    if (std::find(key_columns.begin(), key_columns.end(), *c) == key_columns.end()) key_columns.push_back(*c);
  }
  for (int c : catalog.design_columns()) {
    if (c != height_column && std::find(key_columns.begin(), key_columns.end(), c) == key_columns.end()) {
      key_columns.push_back(c);
    }
  }
  return key_columns;
}

// Why a group's heights (ascending) and margins hold no bracket with unstable below and stable above.
std::string NoBracketReason(const std::vector<double>& h, const std::vector<double>& s, int crossings) {
  if (h.size() < 2) return "fewer than two heights with a finite stability margin";
  const std::string range = Metres(h.front()) + " to " + Metres(h.back());
  if (std::all_of(s.begin(), s.end(), [](double v) { return v < 0; }))
    return "stable at every grid height from " + range;
  if (std::all_of(s.begin(), s.end(), [](double v) { return v >= 0; }))
    return "unstable at every grid height from " + range;
  return "no grid height has unstable below and stable above (" + std::to_string(crossings) +
         " sign changes from " + range + ")";
}

// Refines `point`'s grid bracket [grid_lower_height_m, grid_upper_height_m], whose archived margins
// are `stored` (lower, upper), on the run's model rebuilt from the archive: sets height_m, its
// H/b and bracket width, or the reason why not (the model does not reproduce the archived margins,
// or the refinement finds no boundary).
void RefineBracket(const LongitudinalModel& model, double speed_mps, std::pair<double, double> stored,
                   double tolerance_m, double wingspan_m, ArchiveBoundaryPoint& point) {
  const double lower = point.grid_lower_height_m, upper = point.grid_upper_height_m;
  // The rebuilt model must reproduce the archived σ at both ends of the bracket.
  for (const auto& [height, margin] : {std::pair{lower, stored.first}, std::pair{upper, stored.second}}) {
    const double again = StabilityMargin(model, height, speed_mps);
    if (!(std::abs(again - margin) <=
          kMarginRelativeAgreement * std::abs(margin) + kMarginAbsoluteAgreement)) {
      point.reason = "the model rebuilt from the archive gives sigma = " + Number(again) +
                     " 1/s at H = " + Metres(height) + " where the archive has " + Number(margin) +
                     " 1/s (made by another engine version?); not refined";
      return;
    }
  }
  BoundaryOptions refine;
  refine.lower_height_m = lower;
  refine.upper_height_m = upper;
  refine.samples_per_segment = kRefineSamplesPerSegment;
  refine.tolerance_m = tolerance_m;
  point.refined = FindBoundary(model, speed_mps, refine);
  if (!point.refined.height_m) {
    point.reason = "refinement inside the grid bracket " + Metres(lower) + " to " + Metres(upper) +
                   " found none: " + point.refined.reason;
    return;
  }
  point.height_m = point.refined.height_m;
  point.height_over_span = *point.refined.height_m / wingspan_m;
  for (const auto& crossing : point.refined.crossings) {
    if (crossing.height_m == *point.height_m) point.bracket_width_m = crossing.bracket_width_m;
  }
}

// Every complete ok run's height and σ with the index of its group (its values of the key axes,
// appended to `group_keys` in order of first appearance), sorted by group then height; counts the
// runs used and skipped in `boundary`. Reads block by block.
std::vector<Sample> ReadSamples(const ArchiveReader& archive, const ColumnCatalog& catalog, int height_column,
                                int margin_column, const std::vector<int>& key_columns,
                                std::vector<std::vector<double>>& group_keys, ArchiveBoundary& boundary) {
  std::map<std::vector<double>, std::uint32_t> groups;
  std::vector<Sample> samples;
  std::vector<ColumnValues> keys(key_columns.size());
  ColumnValues heights, margins;
  std::vector<double> key(key_columns.size());
  for (std::int64_t first = 0; first < archive.run_count(); first += kChunkRows) {
    const std::int64_t count = std::min(kChunkRows, archive.run_count() - first);
    const std::vector<std::int8_t> status = archive.ReadStatus(first, count);  // before the values: snapshots
    ReadColumn(archive, catalog.column(height_column), first, count, heights);
    ReadColumn(archive, catalog.column(margin_column), first, count, margins);
    for (std::size_t k = 0; k < key_columns.size(); ++k) {
      ReadColumn(archive, catalog.column(key_columns[k]), first, count, keys[k]);
    }
    for (std::size_t r = 0; r < static_cast<std::size_t>(count); ++r) {
      if (status[r] != 1 || !std::isfinite(margins.numbers[r]) || !std::isfinite(heights.numbers[r])) {
        ++boundary.runs_skipped;
        continue;
      }
      for (std::size_t k = 0; k < key_columns.size(); ++k) key[k] = keys[k].numbers[r];
      auto [it, inserted] = groups.try_emplace(key, static_cast<std::uint32_t>(group_keys.size()));
      if (inserted) group_keys.push_back(key);
      samples.push_back(Sample{heights.numbers[r], margins.numbers[r], it->second});
      ++boundary.runs_used;
    }
  }
  std::sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) {
    return a.group != b.group ? a.group < b.group : a.height_m < b.height_m;
  });
  return samples;
}

// Where each key axis, and height_m, sits in the design's columns (to rebuild a run's design values).
struct DesignSlots {
  std::vector<int> of_key;  // -1: not a design column
  int height = -1;
};

// The slots of the key axes `key_names` and of height_m among the design's parameters.
DesignSlots FindDesignSlots(const std::vector<ParameterId>& design_ids,
                            const std::vector<std::string>& key_names) {
  DesignSlots slots;
  slots.of_key.assign(key_names.size(), -1);
  for (std::size_t d = 0; d < design_ids.size(); ++d) {
    const ParameterInfo& info = ParameterCatalog()[static_cast<std::size_t>(design_ids[d])];
    if (info.name == "height_m") slots.height = static_cast<int>(d);
    for (std::size_t k = 0; k < key_names.size(); ++k) {
      // An archive written before a rename names the axis by its older name (RenamedParameters).
      if (key_names[k] == info.name || key_names[k] == info.identity_name)
        slots.of_key[k] = static_cast<int>(d);
    }
  }
  return slots;
}

// One group's boundary from its samples [begin, end) (sorted by height): its grid bracket, the
// highest with unstable below and stable above, refined on the group's model (or the reason why not).
void LocateGroupBoundary(const std::vector<Sample>& samples, std::size_t begin, std::size_t end,
                         const std::vector<double>& key_values, const DesignSlots& slots,
                         ArchiveRunModels& models, ParameterId speed_id,
                         const BoundaryExtractionOptions& options, double wingspan_m,
                         ArchiveBoundaryPoint& point) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // One σ per height (a repeated height keeps its first run).
  std::vector<double> h, s;
  for (std::size_t i = begin; i < end; ++i) {
    if (!h.empty() && samples[i].height_m == h.back()) continue;
    h.push_back(samples[i].height_m);
    s.push_back(samples[i].margin_per_s);
  }
  point.key_values = key_values;
  point.heights = static_cast<std::int64_t>(h.size());
  point.grid_lower_height_m = point.grid_upper_height_m = point.bracket_width_m = nan;
  std::optional<std::size_t> bracket;  // index of the lower end
  for (std::size_t i = 0; i + 1 < h.size(); ++i) {
    if ((s[i] < 0) != (s[i + 1] < 0)) ++point.grid_crossings;
    if (s[i] >= 0 && s[i + 1] < 0) bracket = i;  // ascending: the last one found is the highest
  }
  std::vector<double> design_values(models.design_parameters().size());
  for (std::size_t k = 0; k < slots.of_key.size(); ++k) {
    if (slots.of_key[k] >= 0) design_values[static_cast<std::size_t>(slots.of_key[k])] = point.key_values[k];
  }
  design_values[static_cast<std::size_t>(slots.height)] = h.front();
  point.parameters = models.Parameters(design_values);
  if (!bracket) {
    point.reason = NoBracketReason(h, s, point.grid_crossings);
    return;
  }
  const double lower = h[*bracket], upper = h[*bracket + 1];
  point.grid_lower_height_m = lower;
  point.grid_upper_height_m = upper;
  const double speed_mps = point.parameters[static_cast<std::size_t>(speed_id)];
  RefineBracket(models.Model(point.parameters), speed_mps, {s[*bracket], s[*bracket + 1]},
                options.tolerance_m, wingspan_m, point);
}

}  // namespace

ArchiveBoundary ExtractBoundary(const ArchiveReader& archive, const ColumnCatalog& catalog,
                                ArchiveRunModels& models, const BoundaryExtractionOptions& options) {
  const std::string source = archive.path().string();
  const auto height_column = catalog.FindPath(kHeightPath);
  if (!height_column) {
    throw InputError(
        source, "design", "",
        "the design does not sweep height_m; the boundary is the sign change of the stability margin "
        "along height, so the study needs a height_m axis");
  }
  const auto margin_column = catalog.FindPath(kMarginPath);
  if (!margin_column) {
    throw InputError(source, kMarginPath, "",
                     "missing: the study did not run the modes analysis, which stores the stability margin");
  }
  const auto speed_id = FindParameter("speed_mps");
  GESWEEP_DEMAND(speed_id.has_value());

  ArchiveBoundary boundary;
  boundary.archive = source;
  boundary.study_name = archive.StringAttribute("study_name");
  boundary.aircraft_name = models.aircraft().name;
  boundary.wingspan_m = models.aircraft().wingspan_m;
  boundary.tolerance_m = options.tolerance_m;
  boundary.snapshot = archive.snapshot();

  const std::vector<int> key_columns = KeyColumns(catalog, *height_column, options.by);
  for (int c : key_columns) {
    boundary.key_names.push_back(
        catalog.column(c).path.substr(std::string(archive::kDesignGroup).size() + 1));
    boundary.key_units.push_back(catalog.column(c).units);
    boundary.key_levels.push_back(catalog.column(c).levels);
  }

  std::vector<std::vector<double>> group_keys;
  const std::vector<Sample> samples =
      ReadSamples(archive, catalog, *height_column, *margin_column, key_columns, group_keys, boundary);

  // Where each key axis sits in the design's columns (to rebuild a run's design values).
  const DesignSlots slots = FindDesignSlots(models.design_parameters(), boundary.key_names);
  GESWEEP_DEMAND(slots.height >= 0);

  std::size_t begin = 0;
  std::vector<ArchiveBoundaryPoint> points(group_keys.size());
  while (begin < samples.size()) {
    std::size_t end = begin;
    while (end < samples.size() && samples[end].group == samples[begin].group) ++end;
    LocateGroupBoundary(samples, begin, end, group_keys[samples[begin].group], slots, models, *speed_id,
                        options, boundary.wingspan_m, points[samples[begin].group]);
    begin = end;
  }
  std::sort(points.begin(), points.end(), [](const ArchiveBoundaryPoint& a, const ArchiveBoundaryPoint& b) {
    return a.key_values < b.key_values;
  });
  boundary.points = std::move(points);
  return boundary;
}

namespace {

// The fields of /analysis/boundary and /analysis/boundary_curve (schemas/products.json).
namespace attribute = product::boundary::attribute;
namespace dataset = product::boundary::dataset;
namespace curve_attribute = product::boundary_curve::attribute;
namespace curve_dataset = product::boundary_curve::dataset;

// The key datasets, one per swept parameter other than height_m (dataset::kKey, named and described
// by the key).
void WriteBoundaryKeys(ProductGroup& g, const ArchiveBoundary& boundary) {
  for (std::size_t k = 0; k < boundary.key_names.size(); ++k) {
    std::vector<double> values;
    for (const auto& p : boundary.points) values.push_back(p.key_values[k]);
    ProductDataset key_dataset =
        g.Numbers(boundary.key_names[k], values, boundary.key_units[k],
                  "Value of the swept parameter " + boundary.key_names[k] + " of this boundary point" +
                      (boundary.key_levels[k].empty() ? "" : " (index of its level; levels attribute)"));
    if (!boundary.key_levels[k].empty()) key_dataset.Attribute("levels", boundary.key_levels[k]);
  }
}

// The datasets of every point.
void WriteBoundaryPoints(ProductGroup& g, const ArchiveBoundary& boundary) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> height, ratio, lower, upper, width;
  std::vector<std::int8_t> found;
  std::vector<std::int32_t> crossings, heights;
  std::vector<std::string> reasons;
  for (const auto& p : boundary.points) {
    height.push_back(p.height_m.value_or(nan));
    ratio.push_back(p.height_over_span.value_or(nan));
    lower.push_back(p.grid_lower_height_m);
    upper.push_back(p.grid_upper_height_m);
    width.push_back(p.bracket_width_m);
    found.push_back(p.height_m ? 1 : 0);
    crossings.push_back(p.grid_crossings);
    heights.push_back(static_cast<std::int32_t>(p.heights));
    reasons.push_back(p.reason);
  }
  g.Numbers(dataset::kHeightM, height);
  g.Numbers(dataset::kHeightOverSpan, ratio);
  ProductDataset found_dataset = g.Numbers(dataset::kFound, found);
  found_dataset.Attribute("levels", std::vector<std::string>{"false", "true"});
  // The archive's convention for integer codes (schemas/archive.md): never stored here, every
  // point is 0 or 1.
  found_dataset.Attribute("fill", std::int64_t{-1});
  g.Numbers(dataset::kGridLowerHeightM, lower);
  g.Numbers(dataset::kGridUpperHeightM, upper);
  g.Numbers(dataset::kBracketWidthM, width);
  g.Numbers(dataset::kGridCrossings, crossings);
  g.Numbers(dataset::kHeights, heights);
  g.Strings(dataset::kReason, reasons);
}

}  // namespace

void WriteBoundaryGroup(const std::filesystem::path& archive, const ArchiveBoundary& boundary,
                        const std::string& command_line) {
  WriteAnalysisProduct(archive, kBoundaryGroup, "the boundary", [&](ProductGroup& g) {
    std::string keys_text;
    for (const auto& name : boundary.key_names) keys_text += (keys_text.empty() ? "" : ", ") + name;
    g.Attribute(attribute::kDescription,
                "Stability boundary H*: for each combination of the swept parameters other than height_m (" +
                    (keys_text.empty() ? std::string("none: one boundary") : keys_text) +
                    "), the highest sign change of results/modes/stability_margin_per_s along "
                    "design/height_m with unstable below and stable above, refined on the run's continuous "
                    "model (docs/report.md)");
    g.Attribute(
        attribute::kMethod,
        "grid bracket from the archived sigma; FindBoundary (the certified Hurwitz finder: roots of Delta4 "
        "and a5, refined by TOMS 748) on the model rebuilt from the archive's aircraft_text and the run's "
        "parameters, inside the bracket");
    g.Attribute(attribute::kKeys, boundary.key_names);
    g.Attribute(attribute::kSourceDataset, kMarginPath);
    g.Attribute(attribute::kAlong, kHeightPath);
    g.Attribute(attribute::kToleranceM, boundary.tolerance_m);
    g.Attribute(attribute::kWingspanM, boundary.wingspan_m);
    g.Attribute(attribute::kAircraftName, boundary.aircraft_name);
    g.Attribute(attribute::kRunsUsed, boundary.runs_used);
    g.Attribute(attribute::kRunsSkipped, boundary.runs_skipped);
    WriteProvenance(g, product::boundary::Layout(), command_line);
    WriteBoundaryKeys(g, boundary);
    WriteBoundaryPoints(g, boundary);
  });
}

void WriteBoundaryCurveGroup(const std::filesystem::path& archive, const BoundaryCurveRecord& curve,
                             const std::string& command_line) {
  WriteAnalysisProduct(archive, kBoundaryCurveGroup, "", [&](ProductGroup& g) {
    g.Attribute(curve_attribute::kDescription,
                "The boundary H*(u0) traced by continuation on the crossing criterion (Delta4 or a5) of "
                "the continuous model over the archive's speed range, every point confirmed by the "
                "certified Hurwitz finder (docs/model.md, 'The boundary by the Hurwitz criterion')");
    g.Attribute(curve_attribute::kWingspanM, curve.wingspan_m);
    WriteProvenance(g, product::boundary_curve::Layout(), command_line);
    g.Numbers(curve_dataset::kSpeedMps, curve.speed_mps);
    g.Numbers(curve_dataset::kHeightM, curve.height_m);
    g.Numbers(curve_dataset::kHeightOverSpan, curve.height_over_span);
    g.Numbers(curve_dataset::kHeightSpeedDerivative, curve.height_speed_derivative);
    g.Numbers(curve_dataset::kBranch, curve.branch);
    g.Numbers(curve_dataset::kEventSpeedMps, curve.event_speed_mps);
    g.Strings(curve_dataset::kEventWhat, curve.event_what);
  });
}

}  // namespace gesweep
