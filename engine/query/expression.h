#pragma once
/// The condition language of `gesweep query --where` (docs/report.md, "--where"): a boolean expression over
/// the per-run columns of an archive.
///
///   condition  := or
///   or         := and ("or" and)*
///   and        := not ("and" not)*
///   not        := "not" not | comparison
///   comparison := sum ( ("==" | "!=" | "<" | "<=" | ">" | ">=") sum
///                     | ["not"] "in" "(" item ("," item)* ")"
///                     | ["not"] ("contains" | "matches") "string" )?
///   item       := ["-"] number | "string" | true | false | inf | nan
///   sum        := product (("+" | "-") product)*
///   product    := unary (("*" | "/" | "%") unary)*
///   unary      := "-" unary | primary
///   primary    := number | "string" | true | false | inf | nan | column
///               | ("abs" | "isnan" | "isfinite") "(" sum ")" | "(" condition ")"
///
/// A column is named as ColumnCatalog resolves names (run_columns.h). A name such as
/// "modes/height_over_span" is one column when it names one; write "a / b" with spaces to divide.
/// A string compares with the text column runs/message, or with a column that has levels
/// (`status == "failed"`, `cdh == "zero"`, `end_event != "touchdown"`), by level name. A column whose
/// levels are false/true (`stable`, `h_derivatives`) is a condition on its own. Missing values
/// (NaN, e.g. a result of a failed run) fail every comparison except "!=" (IEEE 754), and are in no
/// `in` list. `a % b` is the remainder with the sign of b (Python's and NumPy's), NaN when b is 0.
/// `x in (...)` lists literals: numbers, or strings (levels of a level column, or texts of
/// message). `contains` is a substring test, `matches` an RE2 regular expression searched anywhere
/// in the text (anchor it with ^ and $; `(?i)` ignores case); both apply to message, or to a level
/// column, where they select the levels whose names match. Strings have no escapes: a string in
/// "..." may hold ' and one in '...' may hold ".
/// Limits (InputError when passed): nesting of parentheses, function calls, `not` and unary minus
/// 256 levels; the parsed tree 1024 levels (a chain of operators counts one level per operator).
/// Errors are InputError naming the flag and the 1-based column of the expression at fault; an
/// expression longer than 80 characters is echoed by its start and length.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/query/run_columns.h"

namespace gesweep {

/// A parsed, type-checked condition.
class RowFilter {
 public:
  /// Parses `text` against `catalog`. Throws InputError(source "command line", key `flag`, value
  /// the expression) whose message starts "at column N:" for any syntax, name or type error.
  static RowFilter Parse(const std::string& text, const ColumnCatalog& catalog,
                         const std::string& flag = "where");

  RowFilter(RowFilter&&) noexcept;
  RowFilter& operator=(RowFilter&&) noexcept;
  ~RowFilter();

  /// Catalog indices of the columns the condition reads, ascending, without repeats.
  const std::vector<int>& columns() const { return columns_; }

  /// Evaluates the condition for `count` rows: `values[c]` holds the values of catalog column c for
  /// every c in columns() (others unused). Sets keep[r] to 1 where the condition holds, else 0.
  void Evaluate(const std::vector<ColumnValues>& values, std::int64_t count, std::vector<char>& keep) const;

  struct Node;

 private:
  RowFilter();
  std::unique_ptr<Node> root_;
  std::vector<int> columns_;
};

}  // namespace gesweep
