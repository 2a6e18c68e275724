#include "engine/query/aggregate.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "engine/archive/archive_reader.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/common/toml_reader.h"
#include "engine/query/expression.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Buckets of one histogram pass: each pass narrows a rank's range of 64-bit keys by 10 bits, so
// at most 7 passes pin it to one value; 8 KB of counts per sought rank.
constexpr int kHistogramBuckets = 1024;
// One kept value of the order statistics: the unit (group x column, or sought rank) and the value.
struct Entry {
  std::uint32_t owner;
  double value;
};
constexpr std::int64_t kEntryBytes = sizeof(Entry);
constexpr std::int64_t kHistogramBytes = kHistogramBuckets * sizeof(std::int64_t);

bool IsOrderStatistic(AggregateKind kind) {
  return kind == AggregateKind::kMedian || kind == AggregateKind::kQuantile;
}

std::string Trim(const std::string& text) {
  std::size_t a = 0, b = text.size();
  while (a < b && std::isspace(static_cast<unsigned char>(text[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(text[b - 1]))) --b;
  return text.substr(a, b - a);
}

// Splits at commas outside parentheses.
std::vector<std::string> SplitTopLevel(const std::string& text) {
  std::vector<std::string> items;
  std::string current;
  int depth = 0;
  for (char c : text) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == ',' && depth <= 0) {
      items.push_back(current);
      current.clear();
      continue;
    }
    current += c;
  }
  items.push_back(current);
  return items;
}

// A number a person typed in an aggregate item, or nullopt.
std::optional<double> ParseNumber(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

std::string Label(const AggregateSpec& spec, const ColumnCatalog& catalog) {
  if (spec.column < 0) return "count";
  std::string label = std::string(ToString(spec.kind)) + "(" + catalog.column(spec.column).name;
  if (spec.kind == AggregateKind::kQuantile) label += ", " + FormatValue(spec.p);
  if (spec.kind == AggregateKind::kStd && spec.ddof != 1) label += ", " + std::to_string(spec.ddof);
  return label + ")";
}

// Parses one item ("mean(phugoid/*)", "quantile(sink_rate_mps, 0.95)", "count") into specs.
std::vector<AggregateSpec> ParseItem(const std::string& raw, const ColumnCatalog& catalog,
                                     const std::string& flag) {
  const std::string item = Trim(raw);
  auto fail = [&](const std::string& why) -> void {
    throw InputError("command line", flag, "'" + item + "'", why);
  };
  const std::string kForms =
      "expected count, count(c), sum(c), min(c), max(c), mean(c), std(c), std(c, 0), median(c) or "
      "quantile(c, p)";
  if (item.empty()) fail("an empty item; " + kForms);
  const std::size_t open = item.find('(');
  const std::string name = Trim(item.substr(0, open));
  const std::optional<AggregateKind> kind = ParseEnum<AggregateKind>(name);
  if (!kind) {
    std::vector<std::string> words;
    for (const auto& entry : EnumNames<AggregateKind>::kTable) words.emplace_back(entry.name);
    const std::string nearest = NearestName(name, words);
    fail("unknown statistic '" + name + "'" + (nearest.empty() ? "" : " (did you mean " + nearest + "?)") +
         "; " + kForms);
  }
  if (open == std::string::npos) {
    if (*kind != AggregateKind::kCount)
      fail(std::string(ToString(*kind)) + " needs a column: " + name + "(c)");
    AggregateSpec spec;
    spec.label = "count";
    return {spec};
  }
  if (item.back() != ')') fail("expected ')' at the end");
  const std::vector<std::string> arguments = SplitTopLevel(item.substr(open + 1, item.size() - open - 2));
  const std::string column_name = Trim(arguments[0]);
  if (column_name.empty()) fail("expected a column inside the parentheses");
  AggregateSpec base;
  base.kind = *kind;
  const std::size_t extra = arguments.size() - 1;
  if (*kind == AggregateKind::kQuantile) {
    if (extra != 1) fail("quantile takes a column and a probability: quantile(c, 0.95)");
    const auto p = ParseNumber(Trim(arguments[1]));
    if (!p || !(*p >= 0.0 && *p <= 1.0))
      fail("expected a probability 0 <= p <= 1, found '" + Trim(arguments[1]) + "'");
    base.p = *p;
  } else if (*kind == AggregateKind::kStd) {
    if (extra > 1) fail("std takes a column and, optionally, ddof 0 or 1: std(c) or std(c, 0)");
    if (extra == 1) {
      const std::string ddof = Trim(arguments[1]);
      if (ddof != "0" && ddof != "1")
        fail("expected ddof 0 (population) or 1 (sample), found '" + ddof + "'");
      base.ddof = ddof == "0" ? 0 : 1;
    }
  } else if (extra != 0) {
    fail(std::string(ToString(*kind)) + " takes one column: " + name + "(c)");
  }
  const bool wildcard = column_name.find_first_of("*?[") != std::string::npos;
  std::vector<AggregateSpec> specs;
  for (int c : catalog.Expand(column_name, "command line", flag)) {
    const RunColumn& column = catalog.column(c);
    if (column.kind == ColumnKind::kText) {
      if (wildcard) continue;  // a pattern means the numeric columns it matches
      fail(column.name + " is text; statistics take numbers (count counts runs)");
    }
    AggregateSpec spec = base;
    spec.column = c;
    spec.label = Label(spec, catalog);
    specs.push_back(spec);
  }
  if (specs.empty()) fail("the pattern matches only text columns");
  return specs;
}

// Streaming statistics of one column in one group; NaN values are skipped.
struct Moments {
  std::int64_t n = 0;
  double mean = 0, m2 = 0;         // Welford
  double sum = 0, correction = 0;  // Neumaier's compensated sum
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();

  void Add(double x) {
    if (std::isnan(x)) return;
    ++n;
    const double delta = x - mean;
    mean += delta / static_cast<double>(n);
    m2 += delta * (x - mean);
    const double t = sum + x;
    correction += std::abs(sum) >= std::abs(x) ? (sum - t) + x : (x - t) + sum;
    sum = t;
    min = std::min(min, x);
    max = std::max(max, x);
  }
  double Sum() const { return std::isfinite(sum) ? sum + correction : sum; }
  double Mean() const { return n == 0 ? kNaN : Sum() / static_cast<double>(n); }
  double Std(int ddof) const {
    if (n - ddof <= 0) return kNaN;
    if (!std::isfinite(sum)) return kNaN;  // an infinite value: no finite spread (NumPy gives nan)
    return std::sqrt(m2 / static_cast<double>(n - ddof));
  }
};

// The 64-bit key whose unsigned order is the order of doubles (-inf < ... < -0 < +0 < ... < inf).
std::uint64_t OrderKey(double value) {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}
double FromOrderKey(std::uint64_t key) {
  const std::uint64_t bits = (key >> 63) != 0 ? key & ~(std::uint64_t{1} << 63) : ~key;
  return std::bit_cast<double>(bits);
}

// NumPy's _lerp: a + (b - a) t, computed from b for t >= 0.5.
double Lerp(double a, double b, double t) {
  const double d = b - a;
  return t >= 0.5 ? b - d * (1.0 - t) : a + d * t;
}

// The ranks (0-based, among the n sorted values) a statistic needs.
void RanksOf(const AggregateSpec& spec, std::int64_t n, std::vector<std::int64_t>& ranks) {
  if (n <= 0) return;
  if (spec.kind == AggregateKind::kMedian) {
    ranks.push_back((n - 1) / 2);
    ranks.push_back(n / 2);
    return;
  }
  const double h = static_cast<double>(n - 1) * spec.p;
  if (h >= static_cast<double>(n - 1)) {
    ranks.push_back(n - 1);
    return;
  }
  const auto lo = static_cast<std::int64_t>(std::floor(h));
  ranks.push_back(lo);
  ranks.push_back(lo + 1);
}

// The statistic from the values at its ranks (`value_at(rank)`), as NumPy computes it.
template <typename ValueAt>
double OrderStatistic(const AggregateSpec& spec, std::int64_t n, const ValueAt& value_at) {
  if (n <= 0) return kNaN;
  if (spec.kind == AggregateKind::kMedian) {
    const double a = value_at((n - 1) / 2), b = value_at(n / 2);
    return n % 2 == 1 ? a : (a + b) / 2.0;
  }
  const double h = static_cast<double>(n - 1) * spec.p;
  if (h >= static_cast<double>(n - 1)) return value_at(n - 1);
  const double lo = std::floor(h);
  const auto rank = static_cast<std::int64_t>(lo);
  return Lerp(value_at(rank), value_at(rank + 1), h - lo);
}

// A value as a group key: NaN one group, -0 and +0 one group.
double Canonical(double value) {
  if (std::isnan(value)) return kNaN;
  return value == 0.0 ? 0.0 : value;
}

struct Group {
  std::vector<QueryCell> key;
  std::int64_t rows = 0;
  std::vector<Moments> moments;  // one per statistics column
};

// Strict weak order of groups by their key cells: numbers ascending with NaN last, texts
// lexicographically, exact unsigned integers by value.
bool KeyBefore(const std::vector<const RunColumn*>& columns, const std::vector<QueryCell>& a,
               const std::vector<QueryCell>& b) {
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const RunColumn& column = *columns[c];
    if (column.kind == ColumnKind::kText) {
      const int order = a[c].text.compare(b[c].text);
      if (order != 0) return order < 0;
      continue;
    }
    if (column.kind == ColumnKind::kUnsigned) {
      if (a[c].text.size() != b[c].text.size()) return a[c].text.size() < b[c].text.size();
      const int order = a[c].text.compare(b[c].text);
      if (order != 0) return order < 0;
      continue;
    }
    const bool a_nan = std::isnan(a[c].number), b_nan = std::isnan(b[c].number);
    if (a_nan != b_nan) return b_nan;
    if (!a_nan && a[c].number != b[c].number) return a[c].number < b[c].number;
  }
  return false;
}

// One sought rank of one unit (group x order-statistics column) while passes narrow it.
struct Target {
  std::uint32_t unit = 0;
  std::int64_t rank = 0;
  std::uint64_t low = 0, high = ~std::uint64_t{0};  // key range that holds the value (inclusive)
  std::int64_t below = 0;                           // the unit's values with a key under `low`
  std::int64_t inside = 0;                          // its values with a key in [low, high]
  bool found = false;
  double value = kNaN;
};

// The rows of the archive the first pass selected, one bit each.
class RowSet {
 public:
  void Resize(std::int64_t rows) { words_.assign(static_cast<std::size_t>((rows + 63) / 64), 0); }
  void Set(std::int64_t row) { words_[static_cast<std::size_t>(row / 64)] |= std::uint64_t{1} << (row % 64); }
  bool Has(std::int64_t row) const {
    return (words_[static_cast<std::size_t>(row / 64)] >> (row % 64) & 1U) != 0;
  }
  bool Any(std::int64_t first, std::int64_t count) const {
    for (std::int64_t r = first; r < first + count; ++r) {
      if (r % 64 == 0 && r + 64 <= first + count) {
        if (words_[static_cast<std::size_t>(r / 64)] != 0) return true;
        r += 63;
        continue;
      }
      if (Has(r)) return true;
    }
    return false;
  }

 private:
  std::vector<std::uint64_t> words_;
};

class Aggregator {
 public:
  Aggregator(const ArchiveReader& archive, const ColumnCatalog& catalog, const AggregateRequest& request)
      : archive_(archive), catalog_(catalog), request_(request) {}

  QuerySummary Run(QueryRowSink& sink) {
    Prepare();
    FirstPass();
    if (!order_columns_.empty()) FindOrderStatistics();
    Emit(sink);
    return summary_;
  }

 private:
  // Checks every name before any row is read.
  void Prepare() {
    for (const std::string& name : request_.group_by) {
      for (int c : catalog_.Expand(name, "command line", "group_by")) {
        if (std::find(group_columns_.begin(), group_columns_.end(), c) == group_columns_.end())
          group_columns_.push_back(c);
      }
    }
    specs_ = ParseAggregates(
        request_.aggregates.empty() ? std::vector<std::string>{"count"} : request_.aggregates, catalog_);
    if (!request_.where.empty()) filter_.emplace(RowFilter::Parse(request_.where, catalog_, "where"));
    GESWEEP_DEMAND(request_.chunk_rows > 0);
    if (request_.max_groups < 1) {
      throw InputError("command line", "max_groups", std::to_string(request_.max_groups),
                       "expected a count >= 1");
    }
    // The budget holds at least one histogram, so every pass makes progress.
    if (request_.memory_bytes < kHistogramBytes + kEntryBytes) {
      throw InputError("command line", "memory_bytes", std::to_string(request_.memory_bytes),
                       "expected at least " + std::to_string(kHistogramBytes + kEntryBytes) + " bytes");
    }
    moment_slot_.assign(specs_.size(), -1);
    for (std::size_t s = 0; s < specs_.size(); ++s) {
      const AggregateSpec& spec = specs_[s];
      if (spec.column < 0) continue;
      auto slot = [](std::vector<int>& list, int c) {
        const auto it = std::find(list.begin(), list.end(), c);
        if (it != list.end()) return static_cast<int>(it - list.begin());
        list.push_back(c);
        return static_cast<int>(list.size() - 1);
      };
      const int moment = slot(moment_columns_, spec.column);
      moment_slot_[s] = moment;
      if (IsOrderStatistic(spec.kind)) {
        const int order = slot(order_columns_, spec.column);
        order_moment_slot_.resize(order_columns_.size());
        order_moment_slot_[static_cast<std::size_t>(order)] = moment;
      }
    }
    for (int c : group_columns_) output_.push_back(&catalog_.column(c));
    // The aggregate columns: units of their column, integer where the statistic is.
    for (const AggregateSpec& spec : specs_) {
      RunColumn column;
      column.name = spec.label;
      column.statistic = ToString(spec.kind);
      if (spec.column >= 0) {
        const RunColumn& source = catalog_.column(spec.column);
        column.path = source.path;
        const bool keeps_units = spec.kind != AggregateKind::kCount;
        if (keeps_units) column.units = source.units;
        column.integer =
            spec.kind == AggregateKind::kCount ||
            (source.integer && (spec.kind == AggregateKind::kMin || spec.kind == AggregateKind::kMax ||
                                spec.kind == AggregateKind::kSum));
        if (spec.kind == AggregateKind::kMin || spec.kind == AggregateKind::kMax)
          column.levels = source.levels;
        column.description = std::string(ToString(spec.kind)) + " of " + source.path;
      } else {
        column.integer = true;
        column.description = "runs in the group";
      }
      aggregate_columns_.push_back(std::move(column));
    }
    for (const RunColumn& column : aggregate_columns_) output_.push_back(&column);
    // Columns each pass reads besides the filter's.
    for (int c : group_columns_) AddUnique(value_columns_, c);
    for (int c : moment_columns_) AddUnique(value_columns_, c);
    for (int c : group_columns_) AddUnique(later_columns_, c);
    for (int c : order_columns_) AddUnique(later_columns_, c);
  }

  static void AddUnique(std::vector<int>& list, int c) {
    if (std::find(list.begin(), list.end(), c) == list.end()) list.push_back(c);
  }

  // The group key of row i of the block in `values_`.
  void BuildKey(std::size_t i, std::string& key) const {
    key.clear();
    for (int c : group_columns_) {
      const RunColumn& column = catalog_.column(c);
      const ColumnValues& v = values_[static_cast<std::size_t>(c)];
      if (column.kind == ColumnKind::kText) {
        const std::string& text = v.texts[i];
        const auto length = static_cast<std::uint32_t>(text.size());
        key.append(reinterpret_cast<const char*>(&length), sizeof(length));
        key.append(text);
      } else if (column.kind == ColumnKind::kUnsigned) {
        key.append(reinterpret_cast<const char*>(&v.unsigned_values[i]), sizeof(std::uint64_t));
      } else {
        const double value = Canonical(v.numbers[i]);
        key.append(reinterpret_cast<const char*>(&value), sizeof(value));
      }
    }
  }

  // The group of row i, made in the first pass (`create`), or looked up in a later one.
  int GroupOf(std::size_t i, bool create) {
    BuildKey(i, key_);
    const auto it = index_.find(key_);
    if (it != index_.end()) return it->second;
    GESWEEP_DEMAND(create);  // a later pass sees only the first pass's rows
    if (static_cast<std::int64_t>(groups_.size()) >= request_.max_groups) {
      std::string names;
      for (int c : group_columns_) names += (names.empty() ? "" : ",") + catalog_.column(c).name;
      throw RequestError("command line", "group_by", names,
                         "more than " + std::to_string(request_.max_groups) + " groups", "fewer_groups");
    }
    Group group;
    for (int c : group_columns_) {
      const RunColumn& column = catalog_.column(c);
      const ColumnValues& v = values_[static_cast<std::size_t>(c)];
      QueryCell cell;
      if (column.kind == ColumnKind::kText) {
        cell.text = v.texts[i];
      } else if (column.kind == ColumnKind::kUnsigned) {
        cell.number = v.numbers[i];
        cell.text = std::to_string(v.unsigned_values[i]);
      } else {
        cell.number = Canonical(v.numbers[i]);
      }
      group.key.push_back(std::move(cell));
    }
    group.moments.resize(moment_columns_.size());
    groups_.push_back(std::move(group));
    const int id = static_cast<int>(groups_.size() - 1);
    index_.emplace(key_, id);
    return id;
  }

  std::uint32_t Unit(int group, std::size_t order_column) const {
    return static_cast<std::uint32_t>(static_cast<std::size_t>(group) * order_columns_.size() + order_column);
  }

  void Read(const std::vector<int>& columns, std::int64_t first, std::int64_t count,
            const std::vector<int>& skip) {
    for (int c : columns) {
      if (std::find(skip.begin(), skip.end(), c) != skip.end()) continue;
      ReadColumn(archive_, catalog_.column(c), first, count, values_[static_cast<std::size_t>(c)]);
    }
  }

  void FirstPass() {
    summary_.runs = archive_.run_count();
    summary_.snapshot = archive_.snapshot();
    values_.resize(catalog_.columns().size());
    if (group_columns_.empty()) {
      // One group of every matching run, present even when none matches.
      Group all;
      all.moments.resize(moment_columns_.size());
      groups_.push_back(std::move(all));
      index_.emplace(std::string(), 0);
    }
    const std::int64_t budget_entries = request_.memory_bytes / kEntryBytes;
    keeping_ = !order_columns_.empty();
    if (!order_columns_.empty()) selected_.Resize(summary_.runs);
    if (keeping_) {
      // The whole budget at once: address space only, touched (resident) as values come, and never
      // copied by a reallocation that would briefly hold 1.5 budgets. Where even the address space
      // is refused, the buffer grows in steps that stop at the budget.
      try {
        entries_.reserve(static_cast<std::size_t>(budget_entries));
      } catch (const std::bad_alloc&) {
        entries_.reserve(static_cast<std::size_t>(std::min<std::int64_t>(budget_entries, 1 << 20)));
      }
    }
    std::vector<char> keep;
    const std::vector<int> no_skip;
    for (std::int64_t first = 0; first < summary_.runs; first += request_.chunk_rows) {
      const std::int64_t count = std::min(request_.chunk_rows, summary_.runs - first);
      const auto n = static_cast<std::size_t>(count);
      if (!SelectRuns(archive_, catalog_, filter_ ? &*filter_ : nullptr, first, count, values_, keep,
                      summary_))
        continue;
      Read(value_columns_, first, count, filter_ ? filter_->columns() : no_skip);
      for (std::size_t i = 0; i < n; ++i) {
        if (!keep[i]) continue;
        if (!order_columns_.empty()) selected_.Set(first + static_cast<std::int64_t>(i));
        const int g = GroupOf(i, true);
        Group& group = groups_[static_cast<std::size_t>(g)];
        ++group.rows;
        for (std::size_t m = 0; m < moment_columns_.size(); ++m) {
          group.moments[m].Add(values_[static_cast<std::size_t>(moment_columns_[m])].numbers[i]);
        }
        if (!keeping_) continue;
        for (std::size_t j = 0; j < order_columns_.size(); ++j) {
          const double value = values_[static_cast<std::size_t>(order_columns_[j])].numbers[i];
          if (std::isnan(value)) continue;
          if (static_cast<std::int64_t>(entries_.size()) >= budget_entries) {
            // Over budget: the order statistics are found by further passes instead.
            keeping_ = false;
            entries_.clear();
            entries_.shrink_to_fit();
            break;
          }
          if (entries_.size() == entries_.capacity()) {
            entries_.reserve(std::min(2 * entries_.capacity(), static_cast<std::size_t>(budget_entries)));
          }
          entries_.push_back(Entry{Unit(g, j), Canonical(value)});
        }
      }
    }
    summary_.passes = 1;
  }

  std::int64_t UnitCount(std::uint32_t unit) const {
    const std::size_t j = unit % order_columns_.size();
    const std::size_t g = unit / order_columns_.size();
    return groups_[g].moments[static_cast<std::size_t>(order_moment_slot_[j])].n;
  }

  // The targets: every rank a median or quantile needs, per unit, sorted by unit then rank.
  void MakeTargets() {
    std::vector<std::int64_t> ranks;
    for (std::size_t g = 0; g < groups_.size(); ++g) {
      for (std::size_t j = 0; j < order_columns_.size(); ++j) {
        const std::uint32_t unit = Unit(static_cast<int>(g), j);
        const std::int64_t n = UnitCount(unit);
        ranks.clear();
        for (const AggregateSpec& spec : specs_) {
          if (IsOrderStatistic(spec.kind) && spec.column == order_columns_[j]) RanksOf(spec, n, ranks);
        }
        std::sort(ranks.begin(), ranks.end());
        ranks.erase(std::unique(ranks.begin(), ranks.end()), ranks.end());
        for (std::int64_t rank : ranks) {
          Target target;
          target.unit = unit;
          target.rank = rank;
          target.inside = n;
          targets_.push_back(target);
        }
      }
    }
    unit_begin_.assign(groups_.size() * order_columns_.size() + 1, 0);
    for (const Target& target : targets_) ++unit_begin_[target.unit + 1];
    std::partial_sum(unit_begin_.begin(), unit_begin_.end(), unit_begin_.begin());
  }

  // Resolves the targets of the units whose values are all in `entries` (sorted by owner = unit).
  void ResolveFromUnitEntries(std::vector<Entry>& entries) {
    // Grouped by unit (no sort when there is one), then each sought rank by selection, in
    // ascending order on what is left above the previous one: linear time per unit.
    const bool one_owner = std::all_of(entries.begin(), entries.end(),
                                       [&](const Entry& e) { return e.owner == entries.front().owner; });
    if (!one_owner) {
      std::sort(entries.begin(), entries.end(),
                [](const Entry& a, const Entry& b) { return a.owner < b.owner; });
    }
    auto by_value = [](const Entry& a, const Entry& b) { return a.value < b.value; };  // no NaN here
    std::size_t begin = 0;
    while (begin < entries.size()) {
      std::size_t end = begin;
      while (end < entries.size() && entries[end].owner == entries[begin].owner) ++end;
      const std::uint32_t unit = entries[begin].owner;
      GESWEEP_DEMAND(static_cast<std::int64_t>(end - begin) == UnitCount(unit));
      auto low = entries.begin() + static_cast<std::ptrdiff_t>(begin);
      const auto high = entries.begin() + static_cast<std::ptrdiff_t>(end);
      for (std::size_t t = unit_begin_[unit]; t < unit_begin_[unit + 1]; ++t) {
        const auto nth =
            entries.begin() + static_cast<std::ptrdiff_t>(begin + static_cast<std::size_t>(targets_[t].rank));
        std::nth_element(low, nth, high, by_value);
        targets_[t].value = nth->value;
        targets_[t].found = true;
        low = nth;  // every later rank is at or above this one
      }
      begin = end;
    }
  }

  // The order statistics: from the first pass's values when they fit the budget, else by passes.
  void FindOrderStatistics() {
    MakeTargets();
    if (keeping_) {
      ResolveFromUnitEntries(entries_);
      entries_.clear();
      entries_.shrink_to_fit();
      return;
    }
    const std::int64_t budget = request_.memory_bytes;
    while (true) {
      // Plan one pass: whole units that fit, targets whose narrowed range fits, else histograms.
      std::vector<std::uint32_t> collect_units;
      std::vector<std::size_t> collect_targets, histogram_targets;
      std::int64_t left = budget;
      for (std::uint32_t unit = 0; unit + 1 < unit_begin_.size(); ++unit) {
        const std::size_t t0 = unit_begin_[unit], t1 = unit_begin_[unit + 1];
        bool pending = false, narrowed = false;
        for (std::size_t t = t0; t < t1; ++t) {
          pending = pending || !targets_[t].found;
          narrowed = narrowed || targets_[t].inside != UnitCount(unit);
        }
        if (!pending) continue;
        const std::int64_t unit_bytes = UnitCount(unit) * kEntryBytes;
        if (!narrowed && unit_bytes <= budget) {
          if (unit_bytes <= left) {
            collect_units.push_back(unit);
            left -= unit_bytes;
          }
          continue;
        }
        for (std::size_t t = t0; t < t1; ++t) {
          if (targets_[t].found) continue;
          const std::int64_t inside_bytes = targets_[t].inside * kEntryBytes;
          if (inside_bytes <= budget) {
            if (inside_bytes <= left) {
              collect_targets.push_back(t);
              left -= inside_bytes;
            }
          } else if (kHistogramBytes <= left) {
            histogram_targets.push_back(t);
            left -= kHistogramBytes;
          }
        }
      }
      if (collect_units.empty() && collect_targets.empty() && histogram_targets.empty()) return;
      Pass(collect_units, collect_targets, histogram_targets);
    }
  }

  // What each unit does in a pass: collect whole, or act for some of its targets.
  enum class Action : std::uint8_t { kNone, kCollectUnit, kTargets };

  // A pass's plan per unit and target, and each histogram's bucket width (a power of two).
  struct PassRoles {
    std::vector<Action> action;      // per unit
    std::vector<std::int32_t> role;  // per target: -1 idle; -2 collect; >= 0 histogram index
    std::vector<int> shift;          // per histogram: log2 of its bucket width
  };

  // The roles of the units and targets in a pass that collects `collect_units` whole, the values in
  // the ranges of `collect_targets`, and histograms of the ranges of `histogram_targets`.
  PassRoles PlanRoles(const std::vector<std::uint32_t>& collect_units,
                      const std::vector<std::size_t>& collect_targets,
                      const std::vector<std::size_t>& histogram_targets) const {
    PassRoles roles;
    roles.action.assign(unit_begin_.size() - 1, Action::kNone);
    roles.role.assign(targets_.size(), -1);
    for (std::uint32_t unit : collect_units) roles.action[unit] = Action::kCollectUnit;
    for (std::size_t t : collect_targets) {
      roles.action[targets_[t].unit] = Action::kTargets;
      roles.role[t] = -2;
    }
    roles.shift.resize(histogram_targets.size());
    for (std::size_t h = 0; h < histogram_targets.size(); ++h) {
      const Target& target = targets_[histogram_targets[h]];
      roles.action[target.unit] = Action::kTargets;
      roles.role[histogram_targets[h]] = static_cast<std::int32_t>(h);
      const std::uint64_t span = target.high - target.low;
      int s = 0;
      while (s < 64 && (span >> s) >= static_cast<std::uint64_t>(kHistogramBuckets)) ++s;
      roles.shift[h] = s;
    }
    return roles;
  }

  // Reads the selected rows once more: the values of collected units into `unit_entries`, those in
  // collected targets' ranges into `target_entries`, and the histograms' bucket counts into `counts`.
  void ReadPass(const PassRoles& roles, std::vector<Entry>& unit_entries, std::vector<Entry>& target_entries,
                std::vector<std::int64_t>& counts) {
    for (std::int64_t first = 0; first < summary_.runs; first += request_.chunk_rows) {
      const std::int64_t count = std::min(request_.chunk_rows, summary_.runs - first);
      if (!selected_.Any(first, count)) continue;
      Read(later_columns_, first, count, {});
      for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
        if (!selected_.Has(first + static_cast<std::int64_t>(i))) continue;
        const int g = GroupOf(i, false);
        for (std::size_t j = 0; j < order_columns_.size(); ++j) {
          const std::uint32_t unit = Unit(g, j);
          if (roles.action[unit] == Action::kNone) continue;
          const double raw = values_[static_cast<std::size_t>(order_columns_[j])].numbers[i];
          if (std::isnan(raw)) continue;
          const double value = Canonical(raw);
          if (roles.action[unit] == Action::kCollectUnit) {
            unit_entries.push_back(Entry{unit, value});
            continue;
          }
          const std::uint64_t key = OrderKey(value);
          for (std::size_t t = unit_begin_[unit]; t < unit_begin_[unit + 1]; ++t) {
            if (roles.role[t] == -1 || key < targets_[t].low || key > targets_[t].high) continue;
            if (roles.role[t] == -2) {
              target_entries.push_back(Entry{static_cast<std::uint32_t>(t), value});
            } else {
              const auto h = static_cast<std::size_t>(roles.role[t]);
              ++counts[h * kHistogramBuckets + ((key - targets_[t].low) >> roles.shift[h])];
            }
          }
        }
      }
    }
  }

  // Collected ranges: the value of rank (rank - below) among the values in [low, high].
  void ResolveFromTargetEntries(std::vector<Entry>& target_entries) {
    std::sort(target_entries.begin(), target_entries.end(), [](const Entry& a, const Entry& b) {
      return a.owner != b.owner ? a.owner < b.owner : OrderKey(a.value) < OrderKey(b.value);
    });
    for (std::size_t begin = 0; begin < target_entries.size();) {
      std::size_t end = begin;
      while (end < target_entries.size() && target_entries[end].owner == target_entries[begin].owner) ++end;
      Target& target = targets_[target_entries[begin].owner];
      GESWEEP_DEMAND(static_cast<std::int64_t>(end - begin) == target.inside);
      target.value = target_entries[begin + static_cast<std::size_t>(target.rank - target.below)].value;
      target.found = true;
      begin = end;
    }
  }

  // Histograms: the bucket that holds the rank becomes the target's range.
  void NarrowFromHistograms(const std::vector<std::size_t>& histogram_targets, const std::vector<int>& shift,
                            const std::vector<std::int64_t>& counts) {
    for (std::size_t h = 0; h < histogram_targets.size(); ++h) {
      Target& target = targets_[histogram_targets[h]];
      std::int64_t below = target.below;
      for (int b = 0; b < kHistogramBuckets; ++b) {
        const std::int64_t in_bucket = counts[h * kHistogramBuckets + static_cast<std::size_t>(b)];
        if (target.rank < below + in_bucket) {
          const std::uint64_t offset = static_cast<std::uint64_t>(b) << shift[h];
          const std::uint64_t width_minus_one =
              shift[h] >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << shift[h]) - 1;
          const std::uint64_t new_low = target.low + offset;
          const std::uint64_t new_high =
              target.high - new_low <= width_minus_one ? target.high : new_low + width_minus_one;
          target.low = new_low;
          target.high = new_high;
          target.below = below;
          target.inside = in_bucket;
          if (new_low == new_high) {
            target.value = FromOrderKey(new_low);
            target.found = true;
          }
          break;
        }
        below += in_bucket;
      }
    }
  }

  // One more pass over the first pass's rows, collecting or counting values for the planned targets.
  void Pass(const std::vector<std::uint32_t>& collect_units, const std::vector<std::size_t>& collect_targets,
            const std::vector<std::size_t>& histogram_targets) {
    ++summary_.passes;
    const PassRoles roles = PlanRoles(collect_units, collect_targets, histogram_targets);
    std::vector<std::int64_t> counts(histogram_targets.size() * kHistogramBuckets, 0);
    // The planned sizes are known exactly: no reallocation.
    std::vector<Entry> unit_entries, target_entries;
    std::int64_t unit_values = 0, target_values = 0;
    for (std::uint32_t unit : collect_units) unit_values += UnitCount(unit);
    for (std::size_t t : collect_targets) target_values += targets_[t].inside;
    unit_entries.reserve(static_cast<std::size_t>(unit_values));
    target_entries.reserve(static_cast<std::size_t>(target_values));
    ReadPass(roles, unit_entries, target_entries, counts);
    ResolveFromUnitEntries(unit_entries);
    ResolveFromTargetEntries(target_entries);
    NarrowFromHistograms(histogram_targets, roles.shift, counts);
  }

  double TargetValue(std::uint32_t unit, std::int64_t rank) const {
    const auto begin = targets_.begin() + static_cast<std::ptrdiff_t>(unit_begin_[unit]);
    const auto end = targets_.begin() + static_cast<std::ptrdiff_t>(unit_begin_[unit + 1]);
    const auto it =
        std::lower_bound(begin, end, rank, [](const Target& t, std::int64_t r) { return t.rank < r; });
    GESWEEP_DEMAND(it != end && it->rank == rank && it->found);
    return it->value;
  }

  double Statistic(std::size_t s, int g) const {
    const AggregateSpec& spec = specs_[s];
    const Group& group = groups_[static_cast<std::size_t>(g)];
    if (spec.column < 0) return static_cast<double>(group.rows);
    const Moments& m = group.moments[static_cast<std::size_t>(moment_slot_[s])];
    switch (spec.kind) {
      case AggregateKind::kCount:
        return static_cast<double>(m.n);
      case AggregateKind::kSum:
        return m.Sum();
      case AggregateKind::kMin:
        return m.n == 0 ? kNaN : m.min;
      case AggregateKind::kMax:
        return m.n == 0 ? kNaN : m.max;
      case AggregateKind::kMean:
        return m.Mean();
      case AggregateKind::kStd:
        return m.Std(spec.ddof);
      case AggregateKind::kMedian:
      case AggregateKind::kQuantile: {
        const auto j = static_cast<std::size_t>(
            std::find(order_columns_.begin(), order_columns_.end(), spec.column) - order_columns_.begin());
        const std::uint32_t unit = Unit(g, j);
        return OrderStatistic(spec, m.n, [&](std::int64_t rank) { return TargetValue(unit, rank); });
      }
    }
    GESWEEP_UNREACHABLE();
  }

  // The output column --sort names: a group column (any name of it) or an aggregate (its item).
  std::size_t SortColumn() const {
    const std::string& name = request_.sort;
    for (std::size_t s = 0; s < specs_.size(); ++s) {
      if (specs_[s].label == name) return group_columns_.size() + s;
    }
    if (const auto c = catalog_.Find(name)) {
      const auto it = std::find(group_columns_.begin(), group_columns_.end(), *c);
      if (it != group_columns_.end()) return static_cast<std::size_t>(it - group_columns_.begin());
    }
    try {
      const std::vector<AggregateSpec> parsed = ParseAggregates({name}, catalog_, "sort");
      if (parsed.size() == 1) {
        for (std::size_t s = 0; s < specs_.size(); ++s) {
          if (specs_[s] == parsed[0]) return group_columns_.size() + s;
        }
      }
    } catch (const InputError&) {
      // Not an aggregate item either: refused below with the list of output columns.
    }
    std::string names;
    for (const RunColumn* column : output_) names += (names.empty() ? "" : ", ") + column->name;
    throw RequestError("command line", "sort", name, "sort by an output column: one of " + names,
                       "aggregate_sort");
  }

  void Emit(QueryRowSink& sink) {
    std::optional<std::size_t> sort_column;
    if (!request_.sort.empty()) sort_column = SortColumn();
    std::vector<std::vector<QueryCell>> rows;
    rows.reserve(groups_.size());
    for (std::size_t g = 0; g < groups_.size(); ++g) {
      std::vector<QueryCell> cells = groups_[g].key;
      for (std::size_t s = 0; s < specs_.size(); ++s) {
        QueryCell cell;
        cell.number = Statistic(s, static_cast<int>(g));
        cells.push_back(std::move(cell));
      }
      rows.push_back(std::move(cells));
    }
    std::vector<const RunColumn*> key_columns;
    for (int c : group_columns_) key_columns.push_back(&catalog_.column(c));
    std::vector<std::size_t> order(rows.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    auto key_before = [&](std::size_t a, std::size_t b) { return KeyBefore(key_columns, rows[a], rows[b]); };
    std::sort(order.begin(), order.end(), key_before);
    if (sort_column) {
      const std::size_t c = *sort_column;
      const RunColumn& column = *output_[c];
      const bool descending = request_.descending;
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        const QueryCell& x = rows[a][c];
        const QueryCell& y = rows[b][c];
        if (column.kind == ColumnKind::kText) return descending ? x.text > y.text : x.text < y.text;
        const bool x_nan = std::isnan(x.number), y_nan = std::isnan(y.number);
        if (x_nan != y_nan) return y_nan;  // missing values last either way
        if (x_nan) return false;
        return descending ? x.number > y.number : x.number < y.number;
      });
    }
    summary_.groups = static_cast<std::int64_t>(rows.size());
    sink.Begin(output_);
    for (std::size_t k = 0; k < order.size(); ++k) {
      if (request_.limit >= 0 && summary_.shown >= request_.limit) break;
      sink.Row(rows[order[k]]);
      ++summary_.shown;
    }
    sink.End(summary_);
  }

  const ArchiveReader& archive_;
  const ColumnCatalog& catalog_;
  const AggregateRequest& request_;
  std::optional<RowFilter> filter_;
  std::vector<int> group_columns_;
  std::vector<AggregateSpec> specs_;
  std::vector<int> moment_columns_;     // columns with streaming statistics
  std::vector<int> moment_slot_;        // per spec: its slot in moment_columns_ (-1: count of runs)
  std::vector<int> order_columns_;      // columns with medians or quantiles
  std::vector<int> order_moment_slot_;  // per order column: its slot in moment_columns_
  std::vector<int> value_columns_;      // read by the first pass (besides the filter's)
  std::vector<int> later_columns_;      // read by later passes
  std::vector<RunColumn> aggregate_columns_;
  std::vector<const RunColumn*> output_;
  std::vector<ColumnValues> values_;
  std::vector<Group> groups_;
  std::unordered_map<std::string, int> index_;
  std::string key_;
  RowSet selected_;
  bool keeping_ = false;
  std::vector<Entry> entries_;
  std::vector<Target> targets_;
  std::vector<std::size_t> unit_begin_;
  QuerySummary summary_;
};

}  // namespace

std::vector<AggregateSpec> ParseAggregates(const std::vector<std::string>& texts,
                                           const ColumnCatalog& catalog, const std::string& flag) {
  std::vector<AggregateSpec> specs;
  for (const std::string& text : texts) {
    for (const std::string& item : SplitTopLevel(text)) {
      for (AggregateSpec& spec : ParseItem(item, catalog, flag)) {
        if (std::find(specs.begin(), specs.end(), spec) == specs.end()) specs.push_back(std::move(spec));
      }
    }
  }
  return specs;
}

QuerySummary RunAggregateQuery(const ArchiveReader& archive, const ColumnCatalog& catalog,
                               const AggregateRequest& request, QueryRowSink& sink) {
  Aggregator aggregator(archive, catalog, request);
  return aggregator.Run(sink);
}

}  // namespace gesweep
