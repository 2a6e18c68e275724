#pragma once
/// Describe once: each options, config and result struct lists its fields in one member template
///
///     template <class V> void Describe(V& v) {
///       v(Field("step_s", &step_s).Unit("s").Limit("open_loop.step_s").Doc("RK4 step, s"));
///       v(Field("integrator", &kind).Doc("rk4 or dopri5"));
///     }
///
/// (Drake's `Serialize(Archive*)` with DRAKE_NVP, with the unit, the range and the storage added),
/// and every place that needs the list is a visitor of it (docs/architecture.md, "Describe once"):
/// - the study file's [analyses.<name>] table: ReadFields (describe_toml.h), unknown keys refused
///   from the same list;
/// - the command-line flags (engine/cli/described_flags.h), named mechanically from the keys;
/// - the archive columns and their row filling (engine/analyses/described_columns.h);
/// - the CSV and JSON output of `simulate` and `land`;
/// - the check of the schema documents (tests/sweep/schema_sync_test.cc) through ListFields.
///
/// A field's key carries its unit suffix (style guide) and is the same in the study file, on the
/// command line, in the archive (under results/<analysis>/) and in CSV and JSON. The struct stores SI
/// (radians); a key in degrees says so with Scale(kRadiansPerDegree): struct value = key value × scale.
///
/// Cross-field rules stay in a Ceres-style validation function next to the struct; it names fields
/// by KeyOf(object, &object.member), so that its messages use the same keys.

#include <cmath>
#include <concepts>
#include <cstddef>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "engine/common/enum_names.h"
#include "engine/common/errors.h"
#include "engine/common/units.h"  // kRadiansPerDegree, the Scale of a key in degrees

namespace gesweep {

/// Where a setting can be given.
enum class FieldScope : unsigned char {
  kEverywhere,       ///< study file and command line
  kCommandLineOnly,  ///< a flag only: in a sweep the value is a run parameter ([parameters]) or fixed
  kStudyOnly,        ///< a study key only
};

/// How a result field is stored in an archive column.
enum class StoredAs : unsigned char {
  kFloat64,
  kInt32,
  kInt8,
  kNotStored,  ///< in CSV/JSON output only
};

/// One component of an array field (a state vector): its name, unit and description.
struct FieldComponent {
  std::string_view name;
  std::string_view unit;
  std::string_view doc;
};

/// What one field is, apart from where its value lives.
struct FieldAttributes {
  std::string_view key;         ///< study key, flag (mechanically), column leaf, CSV/JSON name
  std::string_view unit = "1";  ///< the key's unit ("s", "m/s", "deg"); "1" for a ratio, count or name
  std::string_view doc;         ///< one line: what it is
  std::string_view limit;       ///< entry of the limits table (input_limits.h), "" for none
  double scale = 1.0;           ///< struct value = key value × scale (kRadiansPerDegree for a key in deg)
  FieldScope scope = FieldScope::kEverywhere;
  StoredAs stored = StoredAs::kFloat64;
  bool in_output = true;  ///< a result field: in CSV/JSON output
  /// NaN is the field's unset state, its value then computed ("automatic"; docs/limits.md, "NaN").
  /// NaN is never an input: a flag, a study key and a keyword argument refuse it; left out, the
  /// field stays unset. CheckFieldRanges passes an unset field.
  bool automatic = false;
  /// A sweep's run parameter of the same key (engine/analyses/parameter_catalog.h): its catalogue
  /// entry (unit, range, default, description) is this field, and a run's value is written into it
  /// (ApplyRunParameters). A flag, never a key of [analyses.<name>] (scope kCommandLineOnly).
  bool run_parameter = false;
  /// An array field: its components; CSV columns and archive columns are prefix + name
  std::span<const FieldComponent> components;
  /// An array field: the components stored in the archive, in archive order (empty: all)
  std::span<const int> stored_components;
  std::string_view component_prefix;  ///< CSV and archive name of component c: prefix + components[c]
  /// A setting's array (NamedComponents): a number per component, each with the key
  /// `<key>.<component>` (ComponentKey) in the parameter catalogue, archives and messages, and the
  /// field's unit, scale and limits-table range. Its flag takes the numbers comma-separated in
  /// component order, its keyword argument a sequence, and its output is an object keyed by
  /// component name.
  bool named_components = false;
};

/// The key of component `c` of a setting's array (FieldAttributes::named_components): "q_weights.delta_u".
std::string ComponentKey(const FieldAttributes& attributes, std::size_t c);

/// What every described item (a Field here, a SeriesField in series.h) has: a key, a unit and a
/// line of description, set in a chain (Self: the item's class; Attributes: its attributes, which
/// have key, unit and doc).
template <class Self, class Attributes>
class DescribedItem {
 public:
  Self& Unit(std::string_view unit) { return Set(&Attributes::unit, unit); }
  Self& Doc(std::string_view doc) { return Set(&Attributes::doc, doc); }
  const Attributes& attributes() const { return attributes_; }

 protected:
  explicit DescribedItem(std::string_view key) { attributes_.key = key; }
  /// Sets one attribute and returns the item, for the chain.
  template <class A, class U>
  Self& Set(A Attributes::*attribute, U value) {
    attributes_.*attribute = value;
    return static_cast<Self&>(*this);
  }
  Attributes attributes_;
};

/// One field: its attributes and a pointer to its value. Built in a chain inside Describe:
/// `v(Field("duration_s", &duration_s).Unit("s").Limit("open_loop.duration_s").Doc("..."))`.
template <class T>
class Field : public DescribedItem<Field<T>, FieldAttributes> {
  using Item = DescribedItem<Field<T>, FieldAttributes>;
  using Item::attributes_;
  using Item::Set;
  using A = FieldAttributes;

 public:
  Field(std::string_view key, T* value) : Item(key), value_(value) {}

  /// The range of the limits table's entry `name` (and its unit must be this field's).
  Field& Limit(std::string_view name) { return Set(&A::limit, name); }
  /// Struct value = key value × scale.
  Field& Scale(double scale) { return Set(&A::scale, scale); }
  /// NaN means "automatic" (FieldAttributes::automatic).
  Field& Automatic() { return Set(&A::automatic, true); }
  Field& CommandLineOnly() { return Set(&A::scope, FieldScope::kCommandLineOnly); }
  /// A sweep's run parameter of the same key (FieldAttributes::run_parameter); a flag only.
  Field& RunParameter() { return Set(&A::run_parameter, true).CommandLineOnly(); }
  Field& StudyOnly() { return Set(&A::scope, FieldScope::kStudyOnly); }
  /// A result's archive column type (default float64).
  Field& Stored(StoredAs stored) { return Set(&A::stored, stored); }
  /// A result field that has no archive column.
  Field& NotStored() { return Stored(StoredAs::kNotStored); }
  /// A result field that is stored but not printed.
  Field& NotInOutput() { return Set(&A::in_output, false); }
  /// A result's array field: component names (static storage), the prefix of their column names and
  /// the components the archive stores (static storage; empty: all).
  Field& Components(std::span<const FieldComponent> names, std::string_view prefix,
                    std::span<const int> stored = {}) {
    Set(&A::components, names).Set(&A::component_prefix, prefix);
    return Set(&A::stored_components, stored);
  }
  /// A setting's array (a std::array of numbers): one number per named component (static storage),
  /// each component's key `<key>.<name>` (FieldAttributes::named_components).
  Field& NamedComponents(std::span<const FieldComponent> names) {
    return Set(&A::components, names).Set(&A::named_components, true);
  }

  T* value() const { return value_; }

 private:
  T* value_;
};

// ---------------------------------------------------------------- kinds of field values

/// A list setting of any length: texts (column names) or numbers (percentiles). On the command line
/// its values are comma-separated (engine/cli/described_flags.h). It has no limits-table range and no
/// scale: the command that reads it checks its values. The study file, ListFields and the front ends'
/// output visitors do not take one (yet): a list is a command-line setting.
template <class T>
concept ListValue = std::same_as<T, std::vector<std::string>> || std::same_as<T, std::vector<double>>;

/// A fixed-size array of doubles (Eigen vector or std::array): `size()` and `operator[]`; a result.
template <class T>
concept DoubleArray = !std::is_arithmetic_v<T> && !ListValue<T> && requires(T & t, int i) {
  { t[i] } -> std::convertible_to<double&>;
  t.size();
};

/// An integer count (steps, calls).
template <class T>
concept IntegerValue = std::integral<T> && !std::same_as<T, bool>;

/// Calls `object.Describe(visitor)` on a const object for a visitor that only reads.
template <class T, class V>
void DescribeConst(const T& object, V& visitor) {
  const_cast<T&>(object).Describe(visitor);  // the read-only visitor never writes through it
}

namespace describe_detail {

struct KeyFinder {
  const void* member;
  std::string_view key;
  template <class U>
  void operator()(const Field<U>& field) {
    if (static_cast<const void*>(field.value()) == member) key = field.attributes().key;
  }
};

}  // namespace describe_detail

/// The key of the field whose value is at `member` (a member of `object`); GESWEEP_DEMAND that
/// there is one. For validation messages in the fields' own keys.
template <class T>
std::string_view KeyOf(const T& object, const void* member) {
  describe_detail::KeyFinder finder{member, {}};
  DescribeConst(object, finder);
  GESWEEP_DEMAND(!finder.key.empty());
  return finder.key;
}

/// The names of an enum's values in table order.
template <NamedEnum E>
std::vector<std::string> EnumChoiceList() {
  std::vector<std::string> names;
  for (const auto& entry : EnumNames<E>::kTable) names.emplace_back(entry.name);
  return names;
}

/// The value kind of a field, for visitors that do not depend on the C++ type.
enum class FieldKind : unsigned char { kNumber, kInteger, kBoolean, kChoice, kText, kArray };

/// A field with its value rendered: what a schema check, a help text or a manifest needs.
struct FieldRecord {
  FieldAttributes attributes;
  FieldKind kind = FieldKind::kNumber;
  std::string default_text;          ///< the current value in the key's unit ("0.015", "true", "rk4")
  std::optional<double> number;      ///< kNumber, kInteger: the current value in the key's unit
  std::vector<std::string> choices;  ///< kChoice: names in table order
  std::vector<std::string> levels;   ///< kChoice: names by code (0, 1, ...)
  std::vector<double> values;        ///< kArray of a setting (named_components): in the key's unit
};

/// A number in the key's unit as a study file or help text would write it.
std::string FieldNumberText(double value);

namespace describe_detail {

struct Recorder {
  std::vector<FieldRecord>* records;
  template <class U>
  void operator()(const Field<U>& field) {
    FieldRecord r;
    r.attributes = field.attributes();
    const U& v = *field.value();
    if constexpr (std::same_as<U, bool>) {
      r.kind = FieldKind::kBoolean;
      r.default_text = v ? "true" : "false";
    } else if constexpr (NamedEnum<U>) {
      r.kind = FieldKind::kChoice;
      r.default_text = std::string(ToString(v));
      r.choices = EnumChoiceList<U>();
      r.levels = EnumLevels<U>();
    } else if constexpr (IntegerValue<U>) {
      r.kind = FieldKind::kInteger;
      r.number = static_cast<double>(v);
      r.default_text = FieldNumberText(*r.number);
    } else if constexpr (std::floating_point<U>) {
      r.kind = FieldKind::kNumber;
      r.number = v / r.attributes.scale;
      r.default_text = FieldNumberText(*r.number);
    } else if constexpr (std::same_as<U, std::string>) {
      r.kind = FieldKind::kText;
      r.default_text = v;
    } else if constexpr (ListValue<U>) {
      static_assert(!sizeof(U*),
                    "a list field is a command-line setting: ListFields and the study file "
                    "do not take one (see ListValue)");
    } else {
      static_assert(DoubleArray<U>,
                    "a described field is a number, integer, bool, named enum, string or array");
      r.kind = FieldKind::kArray;
      if (r.attributes.named_components) {
        for (std::size_t c = 0; c < r.attributes.components.size(); ++c)
          r.values.push_back(v[static_cast<int>(c)] / r.attributes.scale);
      }
    }
    records->push_back(std::move(r));
  }
};

}  // namespace describe_detail

/// Every field of `object` with its current value (so a default-constructed object lists defaults).
template <class T>
std::vector<FieldRecord> ListFields(const T& object) {
  std::vector<FieldRecord> records;
  describe_detail::Recorder recorder{&records};
  DescribeConst(object, recorder);
  return records;
}

/// Throws InputError(source, key, value, expectation) for the first number field outside its
/// limits-table range, in the key's unit (a non-finite number is outside every range).
template <class T>
void CheckFieldRanges(const T& object, const std::string& source);

/// The scope test of a visitor that reads study files (`study` true) or flags.
constexpr bool InScope(const FieldAttributes& a, bool study) {
  return a.scope == FieldScope::kEverywhere ||
         (study ? a.scope == FieldScope::kStudyOnly : a.scope == FieldScope::kCommandLineOnly);
}

/// The check of one number against a limits-table entry (input_limits.h), in the key's unit.
void CheckFieldLimit(const FieldAttributes& attributes, double struct_value, const std::string& source);

namespace describe_detail {

struct RangeChecker {
  const std::string* source;
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if constexpr (std::floating_point<U>) {
      if (a.automatic && std::isnan(*field.value())) return;  // unset: computed
      if (!a.limit.empty()) CheckFieldLimit(a, *field.value(), *source);
    } else if constexpr (DoubleArray<U>) {
      if (!a.named_components || a.limit.empty()) return;
      for (std::size_t c = 0; c < a.components.size(); ++c) {
        const std::string key = ComponentKey(a, c);
        FieldAttributes component = a;
        component.key = key;
        CheckFieldLimit(component, (*field.value())[static_cast<int>(c)], *source);
      }
    }
  }
};

}  // namespace describe_detail

template <class T>
void CheckFieldRanges(const T& object, const std::string& source) {
  describe_detail::RangeChecker checker{&source};
  DescribeConst(object, checker);
}

}  // namespace gesweep
