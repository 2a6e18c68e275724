#pragma once
// What the domain files of the native module share (docs/python.md; module.cc binds them): the
// argument conversions and the errors, the aircraft and the model options, running with the GIL
// released, the dict sink of the records (engine/analyses/records.h) and the visitors of the
// described structs. One file per domain beside it: modes.cc, boundary.cc, simulate.cc, land.cc,
// run.cc, bench.cc.
#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <new>
#include <numbers>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "engine/analyses/records.h"
#include "engine/archive/archive_error.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/archive_writer.h"
#include "engine/cli/failure_text.h"
#include "engine/cli/request_names.h"
#include "engine/common/describe.h"
#include "engine/common/described_values.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/common/output_guard.h"
#include "engine/control/landing_simulation.h"
#include "engine/estimators/local_sensitivity.h"
#include "engine/modal/boundary.h"
#include "engine/modal/modal_analysis.h"
#include "engine/simulation/open_loop.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"

namespace py = pybind11;

namespace gesweep::python {

/// The source an error about a function's argument names (the CLI's is "command line").
inline constexpr const char* kArguments = "argument";

/// How often a waiting call looks at Python's signals and calls the progress callback.
inline constexpr auto kPollInterval = std::chrono::milliseconds(50);

inline py::object& InputErrorType() {
  static py::object type;
  return type;
}
inline py::object& ArchiveErrorType() {
  static py::object type;
  return type;
}

inline std::string Repr(py::handle value) { return py::repr(value).cast<std::string>(); }

/// A Python number as a double; InputError naming `key` when it is not one.
inline double ToNumber(py::handle value, const std::string& key) {
  if (py::isinstance<py::bool_>(value) ||
      !(py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value) ||
        py::hasattr(value, "__float__"))) {
    throw InputError(kArguments, key, Repr(value), "expected a number");
  }
  return value.cast<double>();
}

inline bool ToBool(py::handle value, const std::string& key) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::hasattr(value, "dtype") && py::str(value.attr("dtype")).cast<std::string>() == "bool")
    return value.cast<bool>();
  throw InputError(kArguments, key, Repr(value), "expected True or False");
}

inline std::string ToText(py::handle value, const std::string& key) {
  if (!py::isinstance<py::str>(value)) throw InputError(kArguments, key, Repr(value), "expected a string");
  return value.cast<std::string>();
}

/// A Python int (or a NumPy integer: anything with __index__, never a bool or a float) within the
/// limits table's whole entry `limit` (a seed, a run index), as U: parsed exactly from its digits by
/// ParseExactInteger, as the command line's flags are; InputError naming `key` otherwise.
template <class U>
inline U ToCount(py::handle value, const std::string& key, const std::string& limit) {
  const bool integral =
      !py::isinstance<py::bool_>(value) && !py::isinstance<py::float_>(value) &&
      py::hasattr(value, "__index__") &&
      !(py::hasattr(value, "dtype") && py::str(value.attr("dtype")).cast<std::string>() == "bool");
  if (!integral)
    throw InputError(
        kArguments, key, Repr(value),
        "expected an int, " + DescribeLimit(RequireInputLimit(limit)) + " (not a float or a bool)");
  PyObject* index = PyNumber_Index(value.ptr());
  if (index == nullptr) {
    PyErr_Clear();
    throw InputError(kArguments, key, Repr(value),
                     "expected an int, " + DescribeLimit(RequireInputLimit(limit)));
  }
  const std::string digits = py::str(py::reinterpret_steal<py::object>(index)).cast<std::string>();
  const std::uint64_t number = ParseExactInteger(digits, limit, kArguments, key);
  GESWEEP_DEMAND(number <= static_cast<std::uint64_t>(std::numeric_limits<U>::max()));
  return static_cast<U>(number);
}

// ---------------------------------------------------------------- the model

/// An aircraft file loaded once, and the model of the options used last (a boundary search or a
/// modes call at the same options builds nothing).
class PyAircraft {
 public:
  explicit PyAircraft(Aircraft aircraft) : aircraft_(std::move(aircraft)) {}
  const Aircraft& aircraft() const { return aircraft_; }

  std::shared_ptr<const LongitudinalModel> Model(const ModelOptions& options) const {
    std::lock_guard lock(mutex_);
    if (model_ && model_->options() == options) return model_;
    model_ = std::make_shared<const LongitudinalModel>(aircraft_, options);
    return model_;
  }

 private:
  Aircraft aircraft_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const LongitudinalModel> model_;
};

// ---------------------------------------------------------------- running with the GIL released

/// Runs `work(cancel)` on a thread of its own while this one, holding the GIL between waits, looks
/// at Python's signals every kPollInterval and calls `tick` (may be empty). A KeyboardInterrupt (or
/// any exception a signal handler or `tick` raises) sets `cancel`, waits for the work to stop, and is
/// raised again; an exception of the work is raised here.
inline void RunInterruptible(const std::function<void(const std::atomic<bool>*)>& work,
                             const std::function<void()>& tick = {}) {
  std::atomic<bool> cancel{false};
  std::promise<void> finished;
  std::future<void> done = finished.get_future();
  std::thread worker([&] {
    try {
      work(&cancel);
      finished.set_value();
    } catch (...) {
      finished.set_exception(std::current_exception());
    }
  });
  std::exception_ptr interrupted;
  while (true) {
    bool ready = false;
    {
      py::gil_scoped_release release;
      ready = done.wait_for(kPollInterval) == std::future_status::ready;  // returns as soon as it ends
    }
    if (ready) break;
    if (interrupted) continue;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (tick) tick();
    } catch (...) {
      interrupted = std::current_exception();
      cancel = true;
    }
  }
  worker.join();
  if (interrupted) std::rethrow_exception(interrupted);
  done.get();  // the work's exception, if any
}

// ---------------------------------------------------------------- records

/// The module's sink of the records of engine/analyses/records.h (and of VisitOutputs): a dict, NaN
/// as nan, a missing part as None, a complex number as complex, a range as a tuple. The command
/// line renders the same records as JSON (engine/cli/record_json.h).
struct DictRecordSink {
  py::dict* out;
  template <class X>
  void Plain(const std::string& key, const X& value) {
    (*out)[py::str(key)] = value;
  }
  void Number(const std::string& key, double value) { Plain(key, value); }
  void Array(const std::string& key, const std::vector<double>& values,
             const std::vector<std::string>& names) {
    Plain(key, values);
    Plain(key + "_names", names);
  }
  void Null(const std::string& key) { (*out)[py::str(key)] = py::none(); }
  void Complex(const std::string& key, std::complex<double> z) { Plain(key, z); }
  void Complexes(const std::string& key, const std::vector<std::complex<double>>& values) {
    py::list list;
    for (const auto z : values) list.append(z);
    (*out)[py::str(key)] = list;
  }
  void Numbers(const std::string& key, std::span<const double> values) {
    py::list list;
    for (const double v : values) list.append(v);
    (*out)[py::str(key)] = list;
  }
  void Texts(const std::string& key, const std::vector<std::string>& values) { Plain(key, values); }
  void Range(const std::string& key, double low, double high) {
    (*out)[py::str(key)] = py::make_tuple(low, high);
  }
  template <class Names, class Values>
  void NamedNumbers(const std::string& key, const Names& names, const Values& values) {
    py::dict object;
    for (std::size_t i = 0; i < names.size(); ++i) object[py::str(std::string(names[i]))] = values[i];
    (*out)[py::str(key)] = object;
  }
  template <class Fill>
  void Records(const std::string& key, std::size_t count, const Fill& fill) {
    py::list list;
    for (std::size_t i = 0; i < count; ++i) {
      py::dict record;
      DictRecordSink sink{&record};
      fill(i, sink);
      list.append(record);
    }
    (*out)[py::str(key)] = list;
  }
};

template <class Describe>
inline py::dict RecordDict(const Describe& describe) {
  py::dict out;
  DictRecordSink sink{&out};
  describe(sink);
  return out;
}

// ---------------------------------------------------------------- described options and results

/// The settings of a described struct (describe.h) from keyword arguments, by key, in the key's unit;
/// every key it takes is removed from `kwargs`. The same fields as the command line's flags.
struct KwargsReader {
  py::dict* kwargs;
  std::vector<std::string>* keys;
  template <class U>
  void operator()(const Field<U>& field) {
    const FieldAttributes& a = field.attributes();
    if constexpr (SettingValue<U>) {
      if (!InScope(a, false)) return;
      const std::string key(a.key);
      const py::object value = Take(key);
      if (value.is_none()) return;
      if constexpr (std::same_as<U, bool>) {
        *field.value() = ToBool(value, key);
      } else if constexpr (NamedEnum<U>) {
        const std::string text = ToText(value, key);
        const auto parsed = ParseEnum<U>(text);
        if (!parsed) throw InputError(kArguments, key, "'" + text + "'", "expected " + EnumChoices<U>());
        *field.value() = *parsed;
      } else if constexpr (IntegerValue<U>) {
        GESWEEP_DEMAND(!a.limit.empty());  // every integer argument has its range, as its flag
        *field.value() = ToCount<U>(value, key, std::string(a.limit));
      } else {
        static_assert(std::floating_point<U>);
        const double number = ToNumber(value, key);
        // NaN is never an input (docs/limits.md): an automatic setting is left out, or None.
        if (std::isnan(number)) {
          throw InputError(kArguments, key, "nan",
                           a.limit.empty()
                               ? std::string("expected a number")
                               : LimitProblem(RequireInputLimit(a.limit), number) +
                                     (a.automatic ? "; leave it out (or None) for the automatic value" : ""));
        }
        *field.value() = number * a.scale;
      }
    } else if constexpr (DoubleArray<U>) {
      if (a.named_components && InScope(a, false)) TakeNamedArray(a, field.value()->data());
    }
  }

  /// The argument `key` (None when it was not given), removed from the arguments; `key` is known.
  py::object Take(const std::string& key) {
    keys->push_back(key);
    if (!kwargs->contains(key)) return py::none();
    py::object value = (*kwargs)[key.c_str()];
    PyDict_DelItemString(kwargs->ptr(), key.c_str());
    return value;
  }

  /// A setting's array (named_components): a sequence of one number per component, in order.
  void TakeNamedArray(const FieldAttributes& a, double* values) {
    const std::string key(a.key);
    const py::object value = Take(key);
    if (value.is_none()) return;
    const std::size_t count = a.components.size();
    if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value) || py::len(value) != count) {
      std::string order;
      for (std::size_t c = 0; c < count; ++c) order += (c ? ", " : "") + std::string(a.components[c].name);
      throw InputError(kArguments, key, Repr(value),
                       "expected a sequence of " + std::to_string(count) + " numbers in the order " + order);
    }
    const auto numbers = value.cast<py::sequence>();
    for (std::size_t c = 0; c < count; ++c) values[c] = ToNumber(numbers[c], ComponentKey(a, c)) * a.scale;
  }
};

template <class T>
inline py::dict FieldsDict(const T& object) {
  py::dict out;
  DictRecordSink sink{&out};
  VisitOutputs(object, sink);
  return out;
}

/// The settings of a described struct for the Python signature and docstring: key, unit, doc,
/// default (a Python value), choices; the positional keys left out.
template <class T>
inline py::list SettingsList(const T& object, const std::set<std::string>& leave_out) {
  py::list out;
  for (const FieldRecord& r : ListFields(object)) {
    const FieldAttributes& a = r.attributes;
    if (!InScope(a, false) || leave_out.count(std::string(a.key))) continue;
    if (r.kind == FieldKind::kText || (r.kind == FieldKind::kArray && !a.named_components)) continue;
    py::dict entry;
    entry["key"] = std::string(a.key);
    entry["unit"] = std::string(a.unit);
    entry["doc"] = std::string(a.doc);
    entry["limit"] = std::string(a.limit);
    entry["default_text"] = r.default_text;
    if (r.kind == FieldKind::kNumber) {
      entry["default"] = *r.number;
    } else if (r.kind == FieldKind::kInteger) {
      entry["default"] = static_cast<std::int64_t>(*r.number);
    } else if (r.kind == FieldKind::kBoolean) {
      entry["default"] = r.default_text == "true";
    } else if (r.kind == FieldKind::kArray) {  // a setting's array: a sequence, one per component
      std::string names;
      for (const FieldComponent& component : a.components)
        names += (names.empty() ? "" : ", ") + std::string(component.name);
      entry["default"] = r.values;
      entry["doc"] = std::to_string(a.components.size()) + " numbers, one per <component> (" + names +
                     "): " + std::string(a.doc);
    } else {
      entry["default"] = r.default_text;
      entry["choices"] = r.choices;
    }
    if (!a.limit.empty()) {
      if (const InputLimit* limit = FindInputLimit(a.limit)) entry["range"] = DescribeLimit(*limit);
    }
    out.append(entry);
  }
  return out;
}

// ---------------------------------------------------------------- the model options

/// The model options the module reads by hand (ModelOptions::Describe says why), after the described
/// ones: key and description (gesweep.MODEL_OPTIONS).
struct ModelOptionByHand {
  const char* key;
  const char* doc;
};
inline constexpr ModelOptionByHand kModelOptionsByHand[] = {
    {"mass_kg", "Mass override, kg (None: the aircraft's)"},
    {"pitch_inertia_kgm2", "Pitch inertia Iy override, kg m^2 (None: the aircraft's)"},
    {"CDo_scale", "Factor on CDo (the run parameter scale.CDo)"},
    {"scale", "Factors on coefficient columns, e.g. {'CLh': 1.1} (names of the aircraft file)"}};

/// The model options of docs/model.md from keyword arguments (the keys of gesweep.MODEL_OPTIONS):
/// ModelOptions' described fields (KwargsReader), then those of kModelOptionsByHand; every key it
/// takes is removed from `kwargs`.
inline ModelOptions TakeModelOptions(py::dict& kwargs) {
  ModelOptions options;
  if (kwargs.empty()) return options;
  std::vector<std::string> described;
  KwargsReader reader{&kwargs, &described};
  options.Describe(reader);
  CheckFieldRanges(options, kArguments);
  auto take = [&](const char* key) -> std::optional<py::object> {
    if (!kwargs.contains(key)) return std::nullopt;
    py::object value = kwargs[key];
    PyDict_DelItemString(kwargs.ptr(), key);
    if (value.is_none()) return std::nullopt;
    return value;
  };
  if (auto v = take("mass_kg")) options.mass_kg = ToNumber(*v, "mass_kg");
  if (auto v = take("pitch_inertia_kgm2")) options.pitch_inertia_kgm2 = ToNumber(*v, "pitch_inertia_kgm2");
  if (auto v = take("CDo_scale")) options.CDo_scale = ToNumber(*v, "CDo_scale");
  if (auto v = take("scale")) {
    if (!py::isinstance<py::dict>(*v))
      throw InputError(kArguments, "scale", Repr(*v), "expected a dict of coefficient name -> factor");
    for (auto [name, factor] : v->cast<py::dict>()) {
      const std::string text = py::str(name).cast<std::string>();
      const auto c = CoefficientFromName(text);
      if (!c) {
        std::string names;
        for (auto n : kCoefficientNames) names += (names.empty() ? "" : ", ") + std::string(n);
        throw InputError(kArguments, "scale", "'" + text + "'", "expected a coefficient name: " + names);
      }
      std::string key = "scale.";
      key += text;
      options.coefficient_scale[Index(*c)] = ToNumber(factor, key);
    }
  }
  return options;
}

/// Refuses keyword arguments nothing took.
inline void RefuseLeftovers(const py::dict& kwargs, const std::vector<std::string>& known) {
  if (kwargs.empty()) return;
  for (auto [key, value] : kwargs) {
    const std::string name = py::str(key).cast<std::string>();
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InputError(kArguments, name, Repr(value), "unknown option; expected one of: " + list);
  }
}

/// The keys of TakeModelOptions, in gesweep.MODEL_OPTIONS's order.
inline const std::vector<std::string>& ModelOptionKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> list;
    for (const FieldRecord& field : ListFields(ModelOptions{})) {
      if (InScope(field.attributes, false)) list.emplace_back(field.attributes.key);
    }
    for (const ModelOptionByHand& option : kModelOptionsByHand) list.emplace_back(option.key);
    return list;
  }();
  return keys;
}

/// gesweep.MODEL_OPTIONS: key, default (a Python value; None for the aircraft's) and description of
/// each model option, the described ones (SettingsList) first.
inline py::list ModelOptionSettings() {
  const ModelOptions defaults;
  py::list out = SettingsList(defaults, {});
  for (const ModelOptionByHand& option : kModelOptionsByHand) {
    py::dict entry;
    entry["key"] = option.key;
    entry["default"] = std::string_view(option.key) == "CDo_scale"
                           ? py::object(py::float_(defaults.CDo_scale))
                           : py::object(py::none());
    entry["doc"] = option.doc;
    out.append(entry);
  }
  return out;
}

inline std::shared_ptr<const LongitudinalModel> ModelOf(const PyAircraft& aircraft, py::dict& kwargs) {
  return aircraft.Model(TakeModelOptions(kwargs));
}

/// A vector's values as a new NumPy array.
inline py::array_t<double> Array(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

// ---------------------------------------------------------------- the functions module.cc binds

py::dict Modes(const PyAircraft& aircraft,
               const py::array_t<double, py::array::c_style | py::array::forcecast>& heights,
               const py::array_t<double, py::array::c_style | py::array::forcecast>& speeds, int threads,
               const py::object& out, const py::kwargs& kwargs);  // modes.cc
py::dict Boundary(const PyAircraft& aircraft, const py::object& speed_arg, const py::object& method_arg,
                  const py::object& sensitivities_arg, const py::kwargs& kwargs);  // boundary.cc
py::tuple Simulate(const PyAircraft& aircraft, const py::object& height_m, const py::object& speed_mps,
                   const py::object& summary_only_arg, const py::object& output_dt_arg,
                   const py::kwargs& kwargs);  // simulate.cc
py::tuple Land(const PyAircraft& aircraft, const py::object& summary_only_arg, const py::kwargs& kwargs);
py::dict Run(const std::string& study_path, const std::string& archive_path, int threads, py::object progress,
             bool resume, bool force, const std::string& shard_text);  // run.cc
py::dict CheckArchive(const std::string& path);
py::tuple BenchSweepComputeOnly(const std::string& study_path, int threads);  // bench.cc
double BenchBoundarySearch(const PyAircraft& aircraft, double speed_mps, int repetitions);

}  // namespace gesweep::python
