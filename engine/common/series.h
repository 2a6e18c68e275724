#pragma once
/// Describe once, for time series (issue 29): a series lists its quantities once, in a static member
/// template of the struct that holds them,
///
///     template <class V> static void DescribeSeries(V& v) {
///       v(SeriesField("height_m", &LandingSample::height_m).Unit("m").Doc("Height H ..."));
///     }
///
/// and every front end is a visitor of that list: the archive's columns under series/<analysis>/
/// (engine/analyses/described_series.h), the CSV and JSON of `gesweep simulate` and `gesweep land`
/// (engine/cli/series_output.h) and the Python module's dicts (engine/python/support.h). So a quantity
/// has one name and one SI unit everywhere: the key, unit-suffixed as a described field's
/// (describe.h), in radians for an angle.
///
/// A quantity's value lives in one of three kinds of member:
/// - `std::vector<double> Series::*`: one column of a series held column by column (the open loop);
/// - `double Sample::*`: one field of a sample, in a series held as a vector of samples (the landing);
/// - a named enum member of a sample (engine/common/enum_names.h): a choice, stored in the archive as
///   its code and written by CSV, JSON and Python as its name.
/// The time axis is a quantity like the others (`.Axis()`): the archive stores it once, as the
/// analysis's time axis, not as a column.

#include <cstddef>
#include <string_view>
#include <type_traits>
#include <vector>

#include "engine/common/describe.h"  // DescribedItem
#include "engine/common/enum_names.h"

namespace gesweep {

/// When a quantity is in a series.
enum class SeriesPresence : unsigned char {
  kAlways,
  kDisturbance,    ///< the air motion met: only when the run has a moving atmosphere (docs/model.md §9)
  kPitchRateGust,  ///< only with the pitch-rate gust q_g
};

/// Which of the optional quantities a series has.
struct SeriesContents {
  bool disturbance = false;      ///< the run had a moving atmosphere (the archive: always declared)
  bool pitch_rate_gust = false;  ///< the run had the pitch-rate gust

  bool Has(SeriesPresence presence) const {
    switch (presence) {
      case SeriesPresence::kAlways:
        return true;
      case SeriesPresence::kDisturbance:
        return disturbance;
      case SeriesPresence::kPitchRateGust:
        return pitch_rate_gust;
    }
    return false;
  }
};

/// What one quantity is, apart from where its value lives.
struct SeriesAttributes {
  std::string_view key;         ///< archive leaf, CSV column, JSON and dict key
  std::string_view unit = "1";  ///< SI
  std::string_view doc;         ///< one line: what it is (the archive column's description)
  SeriesPresence presence = SeriesPresence::kAlways;
  bool stored = true;  ///< has an archive column (else in CSV, JSON and Python only)
  bool axis = false;   ///< the time axis: the archive's axis dataset, not a column
};

/// One quantity: its attributes and the member that holds it (Member: the class of which it is a
/// member; T: its type). Built in a chain inside DescribeSeries.
template <class Member, class T>
class SeriesField : public DescribedItem<SeriesField<Member, T>, SeriesAttributes> {
  using DescribedItem<SeriesField<Member, T>, SeriesAttributes>::attributes_;

 public:
  SeriesField(std::string_view key, T Member::*member)
      : DescribedItem<SeriesField<Member, T>, SeriesAttributes>(key), member_(member) {}

  SeriesField& Only(SeriesPresence presence) { return this->Set(&SeriesAttributes::presence, presence); }
  /// In CSV, JSON and Python, not in the archive (it follows from stored quantities).
  SeriesField& NotStored() { return this->Set(&SeriesAttributes::stored, false); }
  /// The time axis.
  SeriesField& Axis() { return this->Set(&SeriesAttributes::axis, true).NotStored(); }

  T Member::*member() const { return member_; }

  /// Sample i of the quantity as a number (an enum's code) in `data`: the series (column members) or
  /// the vector of samples (sample members). A column shorter than the series (the air motion of a
  /// run in still air) reads 0.
  template <class Data>
  double Number(const Data& data, std::size_t i) const {
    if constexpr (std::is_same_v<T, std::vector<double>>) {
      const std::vector<double>& column = data.*member_;
      return i < column.size() ? column[i] : 0.0;
    } else if constexpr (NamedEnum<T>) {
      return static_cast<double>(static_cast<int>(data[i].*member_));
    } else {
      return data[i].*member_;
    }
  }

 private:
  T Member::*member_;
};

/// A named enum quantity (a choice): its name at sample i, for CSV, JSON and Python.
template <class Member, NamedEnum E, class Data>
std::string_view SeriesText(const SeriesField<Member, E>& field, const Data& data, std::size_t i) {
  return ToString(data[i].*field.member());
}

/// The number of samples of a series held column by column (its time axis's length) or as a vector
/// of samples.
template <class Data>
std::size_t SeriesLength(const Data& data) {
  if constexpr (requires { data.time_s.size(); }) {
    return data.time_s.size();
  } else {
    return data.size();
  }
}

/// The struct whose DescribeSeries lists the quantities of `Data`: Data itself for a series held
/// column by column, its element for a vector of samples.
template <class Data>
struct SeriesDescription {
  using type = Data;
};
template <class Sample>
struct SeriesDescription<std::vector<Sample>> {
  using type = Sample;
};

/// Calls visit(field) for every quantity of `Data` that `contents` has, in description order.
template <class Data, class Visit>
void ForEachSeriesField(const SeriesContents& contents, Visit&& visit) {
  auto filter = [&](const auto& field) {
    if (contents.Has(field.attributes().presence)) visit(field);
  };
  SeriesDescription<Data>::type::DescribeSeries(filter);
}

}  // namespace gesweep
