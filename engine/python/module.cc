// The native part of the Python module gesweep (docs/python.md): the engine's functions through
// pybind11, with the GIL released while they compute. engine/python/gesweep/__init__.py wraps it in
// the public API (signatures, docstrings from the described fields, DataFrames, open_archive).
// Each domain has its own file (support.h lists them); this one binds them, with the aircraft's facts.
#include <iostream>
#include <mutex>
#include <set>

#include "engine/common/notes.h"
#include "engine/products/product_layouts.h"
#include "engine/python/support.h"

namespace gesweep::python {
namespace {

// An older name a study used (docs/sweep.md, "Renamed parameters"): one line on stderr, once, as the
// command line shows it (std::cerr: a study may be read with the GIL released).
void ShowNote(const std::string& note) {
  static std::mutex mutex;
  static std::set<std::string> shown;
  std::lock_guard lock(mutex);
  if (shown.insert(note).second) std::cerr << "gesweep: note: " << EscapeForMessage(note) << std::endl;
}
// Installed as the module is loaded (before any study is read).
[[maybe_unused]] const bool kShowsNotes = (SetNoteHandler(&ShowNote), true);

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

// What the archive reader (gesweep/_archive.py over gesweep/_hdf5.py) needs of the engine: the archive's
// layout beyond the columns (groups, runs/, the run-status codes from RunStatus's names table, the
// /analysis products, the subset-simulation archive), the keys of the column manifest that
// gesweep/_hdf5.py reads every path and code from.
void BindArchiveLayout(py::module_& m) {
  m.attr("_archive_layout") = py::module_::import("json").attr("loads")(ArchiveLayoutJson().dump());
}

}  // namespace
}  // namespace gesweep::python

PYBIND11_MODULE(_gesweep, m) {
  using namespace gesweep;
  using namespace gesweep::python;
  m.doc() = "The native part of the gesweep module (docs/python.md); use `import gesweep`.";
  m.attr("__version__") = GESWEEP_VERSION;
  m.attr("git_commit") = GESWEEP_GIT_COMMIT;
  BindArchiveLayout(m);

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
  m.def("land_settings", [] { return SettingsList(LandingConfig{}, {}); });
  m.def("model_options", &ModelOptionSettings);
  m.def("classification_levels", [] {
    std::vector<std::string> levels;
    for (auto c : {ModeClassification::kStandard, ModeClassification::kPhugoidSplit,
                   ModeClassification::kShortPeriodSplit, ModeClassification::kAllReal})
      levels.emplace_back(ToString(c));
    return levels;
  });
}
