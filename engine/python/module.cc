// The native part of the Python module gesweep (docs/python.md): the engine's functions through
// pybind11, with the GIL released while they compute. engine/python/gesweep/__init__.py wraps it in
// the public API (signatures, docstrings from the described fields, DataFrames, open_archive).
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
namespace {

/// The source an error about a function's argument names (the CLI's is "command line").
constexpr const char* kArguments = "argument";

/// How often a waiting call looks at Python's signals and calls the progress callback.
constexpr auto kPollInterval = std::chrono::milliseconds(50);

py::object& InputErrorType() {
  static py::object type;
  return type;
}
py::object& ArchiveErrorType() {
  static py::object type;
  return type;
}

std::string Repr(py::handle value) { return py::repr(value).cast<std::string>(); }

/// A Python number as a double; InputError naming `key` when it is not one.
double ToNumber(py::handle value, const std::string& key) {
  if (py::isinstance<py::bool_>(value) ||
      !(py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value) ||
        py::hasattr(value, "__float__"))) {
    throw InputError(kArguments, key, Repr(value), "expected a number");
  }
  return value.cast<double>();
}

bool ToBool(py::handle value, const std::string& key) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::hasattr(value, "dtype") && py::str(value.attr("dtype")).cast<std::string>() == "bool")
    return value.cast<bool>();
  throw InputError(kArguments, key, Repr(value), "expected True or False");
}

std::string ToText(py::handle value, const std::string& key) {
  if (!py::isinstance<py::str>(value)) throw InputError(kArguments, key, Repr(value), "expected a string");
  return value.cast<std::string>();
}

/// A Python int (or a NumPy integer: anything with __index__, never a bool or a float) within the
/// limits table's whole entry `limit` (a seed, a run index), as U: parsed exactly from its digits by
/// ParseExactInteger, as the command line's flags are; InputError naming `key` otherwise.
template <class U>
U ToCount(py::handle value, const std::string& key, const std::string& limit) {
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
    if (model_ && Same(model_->options(), options)) return model_;
    model_ = std::make_shared<const LongitudinalModel>(aircraft_, options);
    return model_;
  }

 private:
  static bool Same(const ModelOptions& a, const ModelOptions& b) {
    return a.h_derivatives == b.h_derivatives && a.cdh == b.cdh && a.interpolation == b.interpolation &&
           a.coefficient_scale == b.coefficient_scale && a.CDo_scale == b.CDo_scale &&
           a.mass_kg == b.mass_kg && a.pitch_inertia_kgm2 == b.pitch_inertia_kgm2 &&
           a.cg_shift_over_chord == b.cg_shift_over_chord;
  }

  Aircraft aircraft_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const LongitudinalModel> model_;
};

/// The model options of docs/model.md from keyword arguments (the keys of gesweep.MODEL_OPTIONS);
/// every key it takes is removed from `kwargs`.
ModelOptions TakeModelOptions(py::dict& kwargs) {
  ModelOptions options;
  if (kwargs.empty()) return options;
  auto take = [&](const char* key) -> std::optional<py::object> {
    if (!kwargs.contains(key)) return std::nullopt;
    py::object value = kwargs[key];
    PyDict_DelItemString(kwargs.ptr(), key);
    if (value.is_none()) return std::nullopt;
    return value;
  };
  if (auto v = take("h_derivatives")) options.h_derivatives = ToBool(*v, "h_derivatives");
  if (auto v = take("cdh")) {
    const std::string text = ToText(*v, "cdh");
    const auto mode = ParseCdhMode(text);
    if (!mode) throw InputError(kArguments, "cdh", "'" + text + "'", "expected polar or zero");
    options.cdh = *mode;
  }
  if (auto v = take("interpolation")) {
    const std::string text = ToText(*v, "interpolation");
    const auto kind = ParseInterpolation(text);
    if (!kind) throw InputError(kArguments, "interpolation", "'" + text + "'", "expected linear or pchip");
    options.interpolation = *kind;
  }
  if (auto v = take("mass_kg")) options.mass_kg = ToNumber(*v, "mass_kg");
  if (auto v = take("pitch_inertia_kgm2")) options.pitch_inertia_kgm2 = ToNumber(*v, "pitch_inertia_kgm2");
  if (auto v = take("cg_shift_over_chord")) options.cg_shift_over_chord = ToNumber(*v, "cg_shift_over_chord");
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
void RefuseLeftovers(const py::dict& kwargs, const std::vector<std::string>& known) {
  if (kwargs.empty()) return;
  for (auto [key, value] : kwargs) {
    const std::string name = py::str(key).cast<std::string>();
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InputError(kArguments, name, Repr(value), "unknown option; expected one of: " + list);
  }
}

const std::vector<std::string>& ModelOptionKeys() {
  static const std::vector<std::string> keys = {
      "h_derivatives",       "cdh",       "interpolation", "mass_kg", "pitch_inertia_kgm2",
      "cg_shift_over_chord", "CDo_scale", "scale"};
  return keys;
}

std::shared_ptr<const LongitudinalModel> ModelOf(const PyAircraft& aircraft, py::dict& kwargs) {
  return aircraft.Model(TakeModelOptions(kwargs));
}

// ---------------------------------------------------------------- running with the GIL released

/// Runs `work(cancel)` on a thread of its own while this one, holding the GIL between waits, looks
/// at Python's signals every kPollInterval and calls `tick` (may be empty). A KeyboardInterrupt (or
/// any exception a signal handler or `tick` raises) sets `cancel`, waits for the work to stop, and is
/// raised again; an exception of the work is raised here.
void RunInterruptible(const std::function<void(const std::atomic<bool>*)>& work,
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

// ---------------------------------------------------------------- modes

/// The per-mode outputs of gesweep.modes, named <mode>/<property> as the archive's results/modes
/// columns (schemas/archive.md).
constexpr std::array<const char*, 3> kModeNames = {"short_period", "phugoid", "height"};
constexpr std::array<const char*, 6> kModeProperties = {
    "eigenvalue_re_per_s",     "eigenvalue_im_per_s", "natural_frequency_radps", "damping_ratio", "period_s",
    "time_to_half_or_double_s"};
constexpr std::array<const char*, 2> kModeFlags = {"oscillatory", "neutral"};

/// Where gesweep.modes writes: the caller's arrays (`out=`, the dict of an earlier call: no new
/// memory, docs/python.md) or new ones. New ones are allocated with malloc, as the engine's own
/// buffers, each a NumPy array that frees its memory when it dies: not through NumPy's allocator,
/// whose MADV_HUGEPAGE made a 10^6-pair call 5-30 % slower on the measuring machine (transparent
/// huge pages there wait for compaction; docs/performance.md, "From Python").
class ModesOutput {
 public:
  /// `out`: None, or a dict of flat arrays (n or n x 5) that Data checks and RefuseUnknown completes.
  ModesOutput(py::ssize_t n, const py::object& out) : n_(n) {
    if (out.is_none()) return;
    if (!py::isinstance<py::dict>(out)) {
      throw InputError(kArguments, "out", Repr(out),
                       "expected the dict of an earlier gesweep.modes call, or None");
    }
    given_ = out.cast<py::dict>();
  }

  /// The `width` values per pair (1, or 5 for the eigenvalues) of output `name`.
  template <class T>
  T* Data(const std::string& name, py::ssize_t width = 1) {
    std::vector<py::ssize_t> shape = {n_};
    if (width > 1) shape.push_back(width);
    if (!given_) {
      const std::size_t bytes = std::max<std::size_t>(static_cast<std::size_t>(n_ * width) * sizeof(T), 1);
      auto* data = static_cast<T*>(std::malloc(bytes));
      if (data == nullptr) throw std::bad_alloc();
      py::capsule owner(data, [](void* memory) { std::free(memory); });
      arrays_[py::str(name)] = py::array_t<T>(shape, data, owner);
      return data;
    }
    const std::string key = "out['" + name + "']";
    if (!given_->contains(name)) throw InputError(kArguments, "out", "", "expected an array '" + name + "'");
    py::object value = (*given_)[py::str(name)];
    const std::string expected = std::string("expected a writeable C-contiguous ") +
                                 DtypeName(py::dtype::of<T>()) + " array of shape " + ShapeText(shape);
    if (!py::isinstance<py::array>(value)) throw InputError(kArguments, key, Repr(value), expected);
    auto array = value.cast<py::array>();
    const std::vector<py::ssize_t> given_shape(array.shape(), array.shape() + array.ndim());
    const bool right = array.dtype().is(py::dtype::of<T>()) && given_shape == shape && array.writeable() &&
                       (array.flags() & py::array::c_style) != 0;
    if (!right) {
      throw InputError(kArguments, key,
                       std::string(array.writeable() ? "a " : "a read-only ") + DtypeName(array.dtype()) +
                           " array of shape " + ShapeText(given_shape),
                       expected);
    }
    ++checked_;
    return static_cast<T*>(array.mutable_data());
  }

  /// With `out=`: refuses names that are not outputs (a misspelt key would be left unwritten).
  void RefuseUnknown() const {
    if (given_ && static_cast<std::size_t>(py::len(*given_)) != checked_) {
      throw InputError(kArguments, "out", "", "expected exactly the keys of an earlier gesweep.modes result");
    }
  }

  /// The arrays written: the new ones, or the caller's dict.
  py::dict Arrays() const { return given_ ? *given_ : arrays_; }

 private:
  static std::string DtypeName(const py::dtype& dtype) {
    return py::str(py::handle(dtype)).cast<std::string>();
  }
  static std::string ShapeText(const std::vector<py::ssize_t>& shape) {
    std::string text = "(";
    for (const py::ssize_t extent : shape) {
      text += std::to_string(extent);
      text += ", ";
    }
    if (shape.size() > 1) text.resize(text.size() - 2);
    if (shape.size() == 1) text.resize(text.size() - 1);
    return text + ")";
  }

  py::ssize_t n_;
  std::optional<py::dict> given_;
  std::size_t checked_ = 0;  // arrays of `out` checked
  py::dict arrays_;
};

/// gesweep.modes: the eigen-analysis at every (H, u) pair, in parallel, the GIL released.
py::dict Modes(const PyAircraft& aircraft,
               const py::array_t<double, py::array::c_style | py::array::forcecast>& heights,
               const py::array_t<double, py::array::c_style | py::array::forcecast>& speeds, int threads,
               const py::object& out, const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  RefuseLeftovers(options, ModelOptionKeys());
  const py::ssize_t n = heights.size();
  if (speeds.size() != n) throw InputError(kArguments, "speed_mps", "", "expected as many speeds as heights");
  const double* h = heights.data();
  const double* u = speeds.data();
  const double wheel = aircraft.aircraft().wheel_contact_height_m;
  const InputLimit& height_limit = RequireInputLimit("height_m");
  const InputLimit& speed_limit = RequireInputLimit("speed_mps");
  for (py::ssize_t i = 0; i < n; ++i) {
    if (!std::isinf(h[i]) && !WithinLimit(height_limit, h[i])) {
      CheckInputLimit("height_m", h[i], kArguments, "height_m");
    }
    if (h[i] < wheel) {
      throw InputError(kArguments, "height_m", ShortNumber(h[i]),
                       "expected heights >= the wheel-contact height " + ShortNumber(wheel) + " m of " +
                           aircraft.aircraft().source_path);
    }
    if (!WithinLimit(speed_limit, u[i])) CheckInputLimit("speed_mps", u[i], kArguments, "speed_mps");
  }

  ModesOutput output(n, out);
  auto* eig = output.Data<std::complex<double>>("eigenvalues", 5);
  double* sig = output.Data<double>("stability_margin_per_s");
  bool* st = output.Data<bool>("stable");
  auto* cl = output.Data<std::int8_t>("classification");
  double* hb = output.Data<double>("height_over_span");
  std::array<std::array<double*, kModeProperties.size()>, kModeNames.size()> prop{};
  std::array<std::array<bool*, kModeFlags.size()>, kModeNames.size()> flag{};
  for (std::size_t m = 0; m < kModeNames.size(); ++m) {
    const std::string prefix = std::string(kModeNames[m]) + "/";
    for (std::size_t p = 0; p < kModeProperties.size(); ++p) {
      prop[m][p] = output.Data<double>(prefix + kModeProperties[p]);
    }
    for (std::size_t f = 0; f < kModeFlags.size(); ++f)
      flag[m][f] = output.Data<bool>(prefix + kModeFlags[f]);
  }
  output.RefuseUnknown();
  const double span = aircraft.aircraft().wingspan_m;
  {
    py::gil_scoped_release release;
    auto body = [&](const tbb::blocked_range<py::ssize_t>& range) {
      for (py::ssize_t i = range.begin(); i != range.end(); ++i) {
        const ModalAnalysis modal = AnalyzeModes(model->StateMatrix(h[i], u[i]));
        for (int k = 0; k < 5; ++k) eig[i * 5 + k] = modal.eigenvalues[k];
        sig[i] = modal.stability_margin_per_s;
        st[i] = modal.stable;
        cl[i] = static_cast<std::int8_t>(modal.classification);
        hb[i] = h[i] / span;
        const ModeProperties* modes[] = {&modal.short_period, &modal.phugoid, &modal.height};
        for (std::size_t m = 0; m < kModeNames.size(); ++m) {
          const ModeProperties& mode = *modes[m];
          const double values[] = {
              mode.eigenvalue.real(), mode.eigenvalue.imag(), mode.natural_frequency_radps,
              mode.damping_ratio,     mode.period_s,          mode.time_to_half_or_double_s};
          static_assert(std::size(values) == kModeProperties.size());
          for (std::size_t p = 0; p < kModeProperties.size(); ++p) prop[m][p][i] = values[p];
          flag[m][0][i] = mode.oscillatory;
          flag[m][1][i] = mode.neutral;
        }
      }
    };
    const int workers = threads > 0 ? threads : tbb::info::default_concurrency();
    if (workers == 1 || n < 1024) {
      body(tbb::blocked_range<py::ssize_t>(0, n));
    } else {
      tbb::task_arena arena(workers);
      arena.execute([&] { tbb::parallel_for(tbb::blocked_range<py::ssize_t>(0, n, 4096), body); });
    }
  }
  return output.Arrays();
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
py::dict RecordDict(const Describe& describe) {
  py::dict out;
  DictRecordSink sink{&out};
  describe(sink);
  return out;
}

// ---------------------------------------------------------------- boundary

py::dict Boundary(const PyAircraft& aircraft, const py::object& speed_arg, const py::object& method_arg,
                  const py::object& sensitivities_arg, const py::kwargs& kwargs) {
  const double speed_mps = ToNumber(speed_arg, "speed_mps");
  const std::string method = ToText(method_arg, "method");
  const bool sensitivities = ToBool(sensitivities_arg, "sensitivities");
  py::dict options_in = kwargs;
  const auto model = ModelOf(aircraft, options_in);
  RefuseLeftovers(options_in, ModelOptionKeys());
  CheckInputLimit("speed_mps", speed_mps, kArguments, "speed_mps");
  BoundaryOptions options;
  if (method == "sampled") {
    options.method = BoundaryMethod::kSampled;
  } else if (method != "hurwitz") {
    throw InputError(kArguments, "method", "'" + method + "'", "expected hurwitz or sampled");
  }
  BoundaryResult result;
  std::optional<BoundarySensitivities> s;
  {
    py::gil_scoped_release release;
    result = FindBoundary(*model, speed_mps, options);
    if (sensitivities) s = ComputeBoundarySensitivities(*model, result);
  }
  return RecordDict(
      [&](auto& sink) { BoundaryRecord(speed_mps, result, model->aircraft().wingspan_m, s, sink); });
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
      keys->push_back(key);
      if (!kwargs->contains(key)) return;
      py::object value = (*kwargs)[key.c_str()];
      PyDict_DelItemString(kwargs->ptr(), key.c_str());
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
    }
  }
};

template <class T>
py::dict FieldsDict(const T& object) {
  py::dict out;
  DictRecordSink sink{&out};
  VisitOutputs(object, sink);
  return out;
}

/// The settings of a described struct for the Python signature and docstring: key, unit, doc,
/// default (a Python value), choices; the positional keys left out.
template <class T>
py::list SettingsList(const T& object, const std::set<std::string>& leave_out) {
  py::list out;
  for (const FieldRecord& r : ListFields(object)) {
    const FieldAttributes& a = r.attributes;
    if (!InScope(a, false) || leave_out.count(std::string(a.key))) continue;
    if (r.kind == FieldKind::kText || r.kind == FieldKind::kArray) continue;
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

// ---------------------------------------------------------------- simulate

py::array_t<double> Array(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

py::tuple Simulate(const PyAircraft& aircraft, const py::object& height_m, const py::object& speed_mps,
                   const py::object& summary_only_arg, const py::object& output_dt_arg,
                   const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  const bool summary_only = ToBool(summary_only_arg, "summary_only");
  std::optional<double> output_dt_s;
  if (!output_dt_arg.is_none()) output_dt_s = ToNumber(output_dt_arg, "output_dt_s");
  OpenLoopConfig config;
  config.start_height_m = ToNumber(height_m, "height_m");
  config.reference_speed_mps = ToNumber(speed_mps, "speed_mps");
  std::vector<std::string> keys;
  KwargsReader reader{&options, &keys};
  config.Describe(reader);
  // The turbulence is RunNoise(seed, run_index), as `gesweep simulate --seed --run-index`.
  for (auto [key, target] : {std::pair{"seed", &config.seed}, std::pair{"run_index", &config.run_index}}) {
    if (!options.contains(key)) continue;
    *target = ToCount<std::uint64_t>(options[key], key, key);
    PyDict_DelItemString(options.ptr(), key);
  }
  keys.insert(keys.end(), ModelOptionKeys().begin(), ModelOptionKeys().end());
  RefuseLeftovers(options, keys);
  if (!summary_only) {
    const double output_dt = output_dt_s ? *output_dt_s : config.integrator.step_s;
    if (output_dt_s) CheckInputLimit("output_dt_s", output_dt, kArguments, "output_dt_s");
    if (config.duration_s / output_dt > 1e7)
      throw InputError(kArguments, "output_dt_s", ShortNumber(output_dt), "expected at most 1e7 samples");
    config.series_interval_s = output_dt;
  }
  try {
    ValidateOpenLoopConfig(*model, config, kArguments);
  } catch (const InputError& e) {
    if (e.key() == "series_interval_s") throw InputError(kArguments, "output_dt_s", e.value(), e.expected());
    throw;
  }
  OpenLoopResult result;
  RunInterruptible(
      [&](const std::atomic<bool>* cancel) { result = SimulateOpenLoop(*model, config, cancel); });
  py::dict run = FieldsDict(config);
  run["aircraft"] = model->aircraft().name;
  run["h_derivatives"] = model->options().h_derivatives;
  run["cdh"] = std::string(ToString(model->options().cdh));
  run["interpolation"] = std::string(ToString(model->options().interpolation));
  run["seed"] = config.seed;
  run["run_index"] = config.run_index;
  py::object series = py::none();
  if (!summary_only) {
    const OpenLoopSeries& s = result.series;
    py::dict columns;
    columns["time_s"] = Array(s.time_s);
    columns["delta_speed_mps"] = Array(s.delta_speed_mps);
    columns["delta_normal_velocity_mps"] = Array(s.delta_normal_velocity_mps);
    columns["pitch_rate_radps"] = Array(s.pitch_rate_radps);
    columns["delta_pitch_rad"] = Array(s.delta_pitch_rad);
    columns["delta_height_m"] = Array(s.delta_height_m);
    columns["height_m"] = Array(s.height_m);
    columns["speed_mps"] = Array(s.speed_mps);
    columns["elevator_rad"] = Array(s.elevator_rad);
    if (!s.u_g_mps.empty()) {  // the air motion met, as the CSV has it: only with a disturbance
      columns["u_g_mps"] = Array(s.u_g_mps);
      columns["w_g_mps"] = Array(s.w_g_mps);
    }
    if (!s.q_g_radps.empty()) columns["q_g_radps"] = Array(s.q_g_radps);
    series = columns;
  }
  return py::make_tuple(run, FieldsDict(result.summary), series);
}

// ---------------------------------------------------------------- land

/// gesweep.land's settings for its signature and docstring: LandingConfig's (Describe) and q_weights,
/// the one array, which each front end reads itself.
py::list LandingSettingsList() {
  const LandingConfig defaults;
  py::list out = SettingsList(defaults, {});
  py::dict q;
  q["key"] = "q_weights";
  q["unit"] = "SI";
  std::string names;
  for (auto name : LandingStateNames()) {
    if (!names.empty()) names += ", ";
    names += name;
  }
  q["doc"] = "9 LQR output weights >= 0 on " + names;
  q["default"] = py::cast(std::vector<double>(defaults.q_weights.begin(), defaults.q_weights.end()));
  out.append(q);
  return out;
}

/// q_weights: a sequence of 9 numbers.
void TakeQWeights(py::dict& options, LandingConfig& config) {
  if (!options.contains("q_weights")) return;
  py::object value = options["q_weights"];
  PyDict_DelItemString(options.ptr(), "q_weights");
  if (value.is_none()) return;
  const std::string expected = "expected a sequence of 9 weights >= 0";
  if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value) ||
      py::len(value) != kLandingStateCount)
    throw InputError(kArguments, "q_weights", Repr(value), expected);
  const auto weights = value.cast<py::sequence>();
  for (int i = 0; i < kLandingStateCount; ++i)
    config.q_weights[static_cast<std::size_t>(i)] =
        ToNumber(weights[static_cast<std::size_t>(i)], "q_weights." + std::string(LandingStateNames()[i]));
}

/// The series' columns of `gesweep land`'s CSV and JSON (LandingSeriesColumns), and phase.
py::dict LandingSeriesDict(const LandingConfig& config, const std::vector<LandingSample>& samples) {
  const auto n = static_cast<py::ssize_t>(samples.size());
  py::dict out;
  for (const LandingSeriesColumn& column : LandingSeriesColumns(config)) {
    py::array_t<double> values(n);
    double* data = values.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) data[i] = column.value(samples[static_cast<std::size_t>(i)]);
    out[py::str(std::string(column.name))] = values;
  }
  py::list phase;
  for (const LandingSample& x : samples) phase.append(std::string(ToString(x.phase)));
  out["phase"] = phase;
  return out;
}

py::tuple Land(const PyAircraft& aircraft, const py::object& summary_only_arg, const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  const bool summary_only = ToBool(summary_only_arg, "summary_only");
  LandingConfig config;
  std::vector<std::string> keys;
  KwargsReader reader{&options, &keys};
  config.Describe(reader);
  TakeQWeights(options, config);
  keys.push_back("q_weights");
  keys.insert(keys.end(), ModelOptionKeys().begin(), ModelOptionKeys().end());
  RefuseLeftovers(options, keys);
  if (summary_only) config.output_interval_s = 0.0;
  ValidateLandingConfig(config, model->aircraft(), kArguments);
  const double time_limit_s = LandingTimeLimit(config, model->aircraft().wheel_contact_height_m);
  if (config.output_interval_s > 0.0 && time_limit_s / config.output_interval_s > 1e7) {
    throw InputError(kArguments, "output_interval_s", ShortNumber(config.output_interval_s),
                     "expected at most 1e7 samples");
  }
  LandingResult r;
  RunInterruptible([&](const std::atomic<bool>* cancel) { r = SimulateLanding(*model, config, cancel); });
  py::dict summary = FieldsDict(r);
  summary["design"] = RecordDict([&](auto& sink) { DesignRecord(r.design, sink); });
  py::object series = py::none();
  if (!summary_only) series = LandingSeriesDict(config, r.series);
  return py::make_tuple(RecordDict([&](auto& sink) { LandingRunRecord(config, r, *model, sink); }), summary,
                        series);
}

// ---------------------------------------------------------------- run

py::dict Run(const std::string& study_path, const std::string& archive_path, int threads, py::object progress,
             bool resume, bool force, const std::string& shard_text) {
  if (resume && force)
    throw InputError(kArguments, "force", "True", "cannot be combined with resume=True (choose one)");
  if (threads < 0 || threads > 4096)
    throw InputError(kArguments, "threads", std::to_string(threads),
                     "expected 1 to 4096 worker threads, or None");
  ShardSpec shard;
  if (!shard_text.empty()) shard = ParseShard(shard_text, "shard");
  Study study = LoadStudy(study_path);
  CheckOutputPath(archive_path, OutputKind::kFile, study.inputs, "archive_path",
                  {archive_path + ".partial", archive_path + ".lock"});
  SweepPlan plan(std::move(study), shard);
  const int workers = threads > 0 ? threads : tbb::info::default_concurrency();
  ArchiveOpenReport opened;
  std::unique_ptr<ArchiveWriter> writer;
  std::string call = "gesweep.run(" + Repr(py::str(study_path)) + ", " + Repr(py::str(archive_path));
  if (threads > 0) call += ", threads=" + std::to_string(threads);
  if (!shard_text.empty()) call += ", shard=" + Repr(py::str(shard_text));
  if (resume) call += ", resume=True";
  if (force) call += ", force=True";
  call += ")";
  {
    py::gil_scoped_release release;
    writer = ArchiveWriter::Open(
        archive_path, plan, RunProvenance{call, workers},
        resume ? ArchiveOpenMode::kResume : (force ? ArchiveOpenMode::kForce : ArchiveOpenMode::kCreate),
        &opened);
  }
  SweepProgress state;
  state.runs_skipped = opened.runs_complete;
  state.runs_to_do = plan.run_count() - opened.runs_complete;
  SweepOutcome outcome;
  const auto start = std::chrono::steady_clock::now();
  auto tick = [&] {
    if (!progress.is_none()) progress(state.runs_done.load(), state.runs_to_do.load());
  };
  std::exception_ptr interrupted;
  try {
    RunInterruptible(
        [&](const std::atomic<bool>* cancel) {
          RunnerOptions options;
          options.threads = workers;
          options.cancel = cancel;
          outcome = RunSweep(plan, opened.pending_blocks, *writer, options, &state);
        },
        tick);
  } catch (py::error_already_set&) {
    interrupted = std::current_exception();  // KeyboardInterrupt, or the callback's exception
  }
  {
    py::gil_scoped_release release;
    writer->Finish();  // closes the archive: what is complete stays for resume=True
  }
  if (interrupted) std::rethrow_exception(interrupted);
  tick();
  py::dict out;
  out["archive"] = archive_path;
  out["runs"] = plan.run_count();
  out["runs_run"] = state.runs_done.load();
  out["runs_ok"] = writer->runs_ok();
  out["runs_failed"] = writer->runs_failed();
  out["runs_pending"] = writer->runs_pending();
  out["cancelled"] = outcome.cancelled;
  out["threads"] = workers;
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

// ---------------------------------------------------------------- the baselines of scripts/bench --python

/// Discards every batch: the compute-only sweep of tests/bench/sweep_throughput.cc.
class DiscardingSink final : public ResultSink {
 public:
  void Write(const ResultBlock& block) override { runs_ += block.rows; }
  std::int64_t runs() const { return runs_; }

 private:
  std::int64_t runs_ = 0;
};

/// Seconds of a study's whole sweep with its batches discarded (`gesweep run` compute-only), and
/// the runs computed.
py::tuple BenchSweepComputeOnly(const std::string& study_path, int threads) {
  SweepPlan plan(LoadStudy(study_path), ShardSpec{});
  std::vector<std::int64_t> blocks(static_cast<std::size_t>(plan.block_count()));
  for (std::size_t b = 0; b < blocks.size(); ++b) blocks[b] = static_cast<std::int64_t>(b);
  DiscardingSink sink;
  RunnerOptions options;
  options.threads = threads;
  double seconds = 0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    RunSweep(plan, blocks, sink, options, nullptr);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return py::make_tuple(seconds, sink.runs());
}

/// Seconds per call of the engine's boundary search alone (FindBoundary in a C++ loop), the model
/// built once, as gesweep.boundary reuses it.
double BenchBoundarySearch(const PyAircraft& aircraft, double speed_mps, int repetitions) {
  const auto model = aircraft.Model(ModelOptions{});
  py::gil_scoped_release release;
  double sink = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < repetitions; ++i) sink += FindBoundary(*model, speed_mps).height_m.value_or(0.0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  GESWEEP_DEMAND(sink == sink);
  return seconds / repetitions;
}

/// Aircraft.<fact> of the Python class: the aircraft file's numbers, SI, under their keys.
constexpr std::pair<const char*, double Aircraft::*> kAircraftNumbers[] = {
    {"wingspan_m", &Aircraft::wingspan_m},
    {"mean_chord_m", &Aircraft::mean_chord_m},
    {"wing_area_m2", &Aircraft::wing_area_m2},
    {"mass_kg", &Aircraft::mass_kg},
    {"pitch_inertia_kgm2", &Aircraft::pitch_inertia_kgm2},
    {"cg_over_chord", &Aircraft::cg_over_chord},
    {"CDo", &Aircraft::CDo},
    {"stall_speed_mps", &Aircraft::stall_speed_mps},
    {"wheel_contact_height_m", &Aircraft::wheel_contact_height_m},
    {"field_elevation_m", &Aircraft::field_elevation_m}};

py::dict AircraftFacts(const PyAircraft& a) {
  const Aircraft& x = a.aircraft();
  py::dict out;
  out["name"] = x.name;
  out["source_path"] = x.source_path;
  for (const auto& [key, member] : kAircraftNumbers) out[key] = x.*member;
  return out;
}

/// The coefficient table: height_m (the free-flight row last, as inf) and one column per tabulated
/// coefficient (aircraft-file names), and CDh as the model derives it with the default options.
py::dict AircraftTable(const PyAircraft& a) {
  const Aircraft& x = a.aircraft();
  std::vector<double> heights = x.table_heights_m;
  heights.push_back(std::numeric_limits<double>::infinity());
  py::dict out;
  out["height_m"] = Array(heights);
  for (int c = 0; c < kTabulatedCount; ++c) {
    std::vector<double> column;
    for (const auto& row : x.rows) column.push_back(row[c]);
    column.push_back(x.free_flight[c]);
    out[py::str(std::string(kCoefficientNames[c]))] = Array(column);
  }
  return out;
}

/// The check every gesweep command makes of an archive before it reads a value (ArchiveReader::Open:
/// the file, its layout, a virtual archive's sources and theirs), for open_archive to make before h5py
/// reads anything: {"snapshot": a sweep is writing it or was killed, "virtual": bool, "notes": what
/// could not be checked}; InputError, in the command's words, naming the file and why otherwise.
py::dict CheckArchive(const std::string& path) {
  bool snapshot = false, is_virtual = false;
  std::vector<std::string> notes;
  {
    py::gil_scoped_release release;
    ArchiveReader reader = ArchiveReader::Open(path);
    snapshot = reader.snapshot();
    is_virtual = reader.is_virtual();
    notes = reader.notes();
  }
  py::dict out;
  out["snapshot"] = snapshot;
  out["virtual"] = is_virtual;
  out["notes"] = notes;
  return out;
}

}  // namespace
}  // namespace gesweep::python

PYBIND11_MODULE(_gesweep, m) {
  using namespace gesweep;
  using namespace gesweep::python;
  m.doc() = "The native part of the gesweep module (docs/python.md); use `import gesweep`.";
  m.attr("__version__") = GESWEEP_VERSION;
  m.attr("git_commit") = GESWEEP_GIT_COMMIT;
  // The run-status codes by name, from RunStatus's names table (the manifest's `run_status`), for
  // the archive reader's comparisons with /runs/status (gesweep/_archive.py).
  py::dict run_status;
  for (const auto& entry : EnumNames<RunStatus>::kTable) {
    run_status[py::str(std::string(entry.name))] = static_cast<int>(entry.value);
  }
  m.attr("_run_status") = run_status;

  // A ValueError, and a TypeError too: an argument of the wrong type is an InputError as well, and
  // code that catches the TypeError Python itself would raise keeps working (docs/python.md).
  py::tuple input_error_bases = py::make_tuple(py::handle(PyExc_ValueError), py::handle(PyExc_TypeError));
  InputErrorType() = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
      "gesweep.InputError",
      "Bad input from a person: names the source (a file, or 'argument'), the key, the value and what was "
      "expected, in one line, as the gesweep command prints it. A ValueError and a TypeError.",
      input_error_bases.ptr(), nullptr));
  m.attr("InputError") = InputErrorType();
  ArchiveErrorType() = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
      "gesweep.ArchiveError", "An archive could not be written or read (I/O, disk full, damage).",
      PyExc_OSError, nullptr));
  m.attr("ArchiveError") = ArchiveErrorType();
  // pybind11's ExceptionTranslator is a function pointer taking the exception_ptr by value.
  py::register_exception_translator([](std::exception_ptr p) {  // NOLINT(performance-unnecessary-value-param)
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      const InputError worded = cli::ForPython(e);
      py::object error = InputErrorType()(py::str(worded.what()));
      error.attr("source") = worded.source();
      error.attr("key") = worded.key();
      error.attr("value") = worded.value();
      error.attr("expected") = worded.expected();
      PyErr_SetObject(InputErrorType().ptr(), error.ptr());
    } catch (const ArchiveError& e) {
      PyErr_SetString(ArchiveErrorType().ptr(), e.what());
    } catch (const std::domain_error& e) {
      // Boost.Math's and the standard library's numerical failures: the project's words, not theirs
      // (issue 26, item 6). pybind11's own exceptions are none of these, and pass on to its translators.
      PyErr_SetString(PyExc_RuntimeError, cli::FailureInWords(e).c_str());
    } catch (const std::overflow_error& e) {
      PyErr_SetString(PyExc_RuntimeError, cli::FailureInWords(e).c_str());
    } catch (const std::underflow_error& e) {
      PyErr_SetString(PyExc_RuntimeError, cli::FailureInWords(e).c_str());
    }
  });

  py::class_<PyAircraft, std::shared_ptr<PyAircraft>>(m, "NativeAircraft")
      .def_static(
          "load",
          [](const std::string& path) { return std::make_shared<PyAircraft>(LoadAircraftFile(path)); })
      .def("facts", &AircraftFacts)
      .def("table", &AircraftTable);
  m.def("modes", &Modes, py::arg("aircraft"), py::arg("height_m"), py::arg("speed_mps"),
        py::arg("threads") = 0, py::arg("out") = py::none());
  m.def("boundary", &Boundary, py::arg("aircraft"), py::arg("speed_mps"), py::arg("method") = "hurwitz",
        py::arg("sensitivities") = false);
  m.def("simulate", &Simulate, py::arg("aircraft"), py::arg("height_m"), py::arg("speed_mps"),
        py::arg("summary_only") = false, py::arg("output_dt_s") = py::none());
  m.def("land", &Land, py::arg("aircraft"), py::arg("summary_only") = false);
  m.def("run", &Run, py::arg("study_path"), py::arg("archive_path"), py::arg("threads") = 0,
        py::arg("progress") = py::none(), py::arg("resume") = false, py::arg("force") = false,
        py::arg("shard") = "");
  m.def("_check_archive", &CheckArchive, py::arg("path"));
  m.def("_bench_sweep_compute_only", &BenchSweepComputeOnly, py::arg("study_path"), py::arg("threads"));
  m.def("_bench_boundary_search", &BenchBoundarySearch, py::arg("aircraft"), py::arg("speed_mps"),
        py::arg("repetitions"));
  m.def("simulate_settings", [] { return SettingsList(OpenLoopConfig{}, {"height_m", "speed_mps"}); });
  m.def("land_settings", &LandingSettingsList);
  m.def("model_option_keys", [] { return ModelOptionKeys(); });
  m.def("classification_levels", [] {
    std::vector<std::string> levels;
    for (auto c : {ModeClassification::kStandard, ModeClassification::kPhugoidSplit,
                   ModeClassification::kShortPeriodSplit, ModeClassification::kAllReal})
      levels.emplace_back(ToString(c));
    return levels;
  });
}
