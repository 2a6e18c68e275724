// gesweep.modes: eigen-analyses over arrays of (H, u0), in parallel, with the GIL released.
#include "engine/python/support.h"

namespace gesweep::python {

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

}  // namespace gesweep::python
