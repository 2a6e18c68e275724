// Fuzz target: the --where parser and evaluator of `gesweep query` (engine/query/expression.h) on
// arbitrary bytes, against a catalogue shaped like a real archive's and a block of awkward values.
// The contract (tests/fuzz/where_contract.h, docs/reliability.md "Fuzzing"): any text parses or
// throws InputError with a one-line message; nothing else may escape, crash, overflow the stack,
// hang, leak or trip a sanitizer; a parsed E evaluates to one 0/1 per row and not (E) to its exact
// complement. Every input that once broke it is kept in tests/query/where_regressions/, which
// query_test replays in every build.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tests/fuzz/where_contract.h"

namespace {

[[noreturn]] void Defect(const char* what, const std::string& detail) {
  std::fprintf(stderr, "where fuzz defect: %s: %.2000s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const gesweep::ColumnCatalog catalog = gesweep::testing::WhereFuzzCatalog();
  static std::int64_t rows = 0;
  static const std::vector<gesweep::ColumnValues> values = gesweep::testing::WhereFuzzValues(catalog, &rows);
  const std::string text(reinterpret_cast<const char*>(data), size);
  gesweep::testing::CheckWhereContract(
      text, catalog, values, rows, [](const char* what, const std::string& detail) { Defect(what, detail); });
  return 0;
}
