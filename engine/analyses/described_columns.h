#pragma once
/// The archive visitor of a described result struct (engine/common/describe.h): its columns under
/// results/<analysis>/ and the filling of one run's row, from the struct's one field list.
///
/// A field's key is its column's leaf; a result's StoredAs is the column type; an enum field's
/// column has the enum's names as levels (codes are the enum's values); an array field has one
/// column per stored component, named prefix + component name.

#include <string>

#include "engine/analyses/analysis.h"
#include "engine/common/describe.h"

namespace gesweep {

/// The column type of a stored field.
ColumnType ColumnTypeOf(StoredAs stored);

namespace describe_detail {

/// DescribedColumns' visitors.
struct ColumnDeclarer {
  OutputSchema* schema;
  const std::string* base;
  int first = -1;
  int count = 0;
  void Add(OutputColumn column) {
    const int index = schema->Add(std::move(column));
    if (first < 0) first = index;
    GESWEEP_DEMAND(index == first + count);  // the columns of one struct are contiguous
    ++count;
  }
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (a.stored == StoredAs::kNotStored) return;
    const std::string path = *base + std::string(a.key);
    if constexpr (NamedEnum<U>) {
      Add(OutputColumn::Integer(ColumnTypeOf(a.stored), path, "1", std::string(a.doc), EnumLevels<U>()));
    } else if constexpr (IntegerValue<U> || std::same_as<U, bool>) {
      Add(OutputColumn::Integer(ColumnTypeOf(a.stored), path, std::string(a.unit), std::string(a.doc)));
    } else if constexpr (std::floating_point<U>) {
      Add(OutputColumn::Real(path, std::string(a.unit), std::string(a.doc)));
    } else if constexpr (DoubleArray<U>) {
      auto add = [&](int c) {
        const FieldComponent& component = a.components[static_cast<std::size_t>(c)];
        Add(OutputColumn::Real(*base + std::string(a.component_prefix) + std::string(component.name),
                               std::string(component.unit),
                               std::string(component.doc) + " " + std::string(a.doc)));
      };
      if (a.stored_components.empty()) {
        for (std::size_t c = 0; c < a.components.size(); ++c) add(static_cast<int>(c));
      } else {
        for (int c : a.stored_components) add(c);
      }
    } else {
      GESWEEP_UNREACHABLE();  // a text field has no column: it must be marked NotStored()
    }
  }
};

struct ColumnFiller {
  OutputRow* row;
  int column;
  void Set(double value) { row->Set(column++, value); }
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if (a.stored == StoredAs::kNotStored) return;
    const U& v = *field.value();
    if constexpr (NamedEnum<U>) {
      Set(static_cast<double>(static_cast<int>(v)));
    } else if constexpr (IntegerValue<U> || std::same_as<U, bool>) {
      Set(static_cast<double>(v));
    } else if constexpr (std::floating_point<U>) {
      Set(v);
    } else if constexpr (DoubleArray<U>) {
      if (a.stored_components.empty()) {
        for (int c = 0; c < static_cast<int>(v.size()); ++c) Set(v[c]);
      } else {
        for (int c : a.stored_components) Set(v[c]);
      }
    }
  }
};

}  // namespace describe_detail

/// The columns of one described result type `T`, declared once and filled per run.
template <class T>
class DescribedColumns {
 public:
  /// Adds a column per stored field of `T` (as a default-constructed T lists them) under `base`
  /// (e.g. "results/open_loop/"), in field order.
  void Declare(OutputSchema& schema, const std::string& base) {
    describe_detail::ColumnDeclarer declarer{&schema, &base};
    T prototype{};
    prototype.Describe(declarer);
    first_ = declarer.first;
    count_ = declarer.count;
  }

  /// Sets this run's values of the declared columns from `result`.
  void Fill(const T& result, OutputRow& row) const {
    describe_detail::ColumnFiller filler{&row, first_};
    DescribeConst(result, filler);
    GESWEEP_DEMAND(filler.column == first_ + count_);
  }

  /// Index of the first declared column; -1 before Declare.
  int first() const { return first_; }
  int count() const { return count_; }

 private:
  int first_ = -1;
  int count_ = 0;
};

}  // namespace gesweep
