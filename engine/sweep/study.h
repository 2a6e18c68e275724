#pragma once
/// A study file (studies/*.toml; format in schemas/study.schema.json and docs/sweep.md): the aircraft,
/// the analyses to run for every run, what to store, the fixed parameters and the design.
///
/// LoadStudy validates the whole study before anything runs: every key known (unknown keys suggest
/// the near one), every value typed and in range, every swept value checked against its parameter
/// and the aircraft, every analysis' required parameter given. Errors are InputError naming the
/// file, the key, the value, what was expected and the line.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/analyses/analysis.h"
#include "engine/common/deflate_encoder.h"
#include "engine/common/output_guard.h"
#include "engine/sweep/design.h"

namespace gesweep {

/// The format version of study files this engine reads.
inline constexpr int kStudyFormatVersion = 1;

/// A parameter held at one value in every run.
struct FixedParameter {
  ParameterId id = 0;
  double value = 0;
};

/// A validated study.
struct Study {
  std::string path;  ///< as given
  std::string text;  ///< the file's full text (archive provenance)
  std::string name;
  std::string description;

  /// The aircraft, when one is named (required when an analysis needs a model).
  std::optional<Aircraft> aircraft;

  /// The analyses, in the order the registry lists them (modes, boundary, open_loop, landing, ...).
  std::vector<std::unique_ptr<Analysis>> analyses;

  StorageOptions storage;
  int chunk_runs = 0;         ///< runs per HDF5 chunk and write batch; 0: chosen by the plan
  int compression_level = 1;  ///< deflate level 0..9 (1: nearly the size of 9 at a fraction of the CPU)
  /// [output] deflate_encoder: zlib (HDF5's own bytes) or libdeflate (the same format, faster).
  DeflateEncoder deflate_encoder = DeflateEncoder::kZlib;
  double max_archive_gb = 1000.0;  ///< refuse designs whose storage estimate exceeds this

  std::vector<FixedParameter> fixed;  ///< from [parameters], catalogue order
  DesignSpec design;

  /// A hash of the parsed study and aircraft (not of comments or layout): shards and resumed
  /// archives must carry the same fingerprint.
  std::uint64_t fingerprint = 0;

  /// Every file the study was read from: the study file, its aircraft file, its design CSV. A
  /// command that writes never replaces one of them (engine/common/output_guard.h).
  std::vector<NamedInput> inputs;

  bool needs_model() const;
  /// The line of the [design] table in the study file, for errors raised after parsing.
  int design_line = 0;
  /// The line of the study's [subset] table (a subset simulation, `gesweep risk`, docs/dispersion.md);
  /// 0 when it has none. `gesweep run` refuses such a study.
  int subset_line = 0;
};

/// Reads and validates a study file. Throws InputError on any problem.
Study LoadStudy(const std::filesystem::path& path);

/// Validates study text; `path` resolves relative paths (aircraft, CSV) and names the file in errors.
Study ParseStudy(const std::string& text, const std::filesystem::path& path);

}  // namespace gesweep
