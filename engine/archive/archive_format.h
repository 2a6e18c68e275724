#pragma once
/// Names of the archive layout (schemas/archive.md is the reference; keep them in step).

#include <cstdint>
#include <string>

namespace gesweep::archive {

/// Version of the layout below; readers refuse a newer major version.
inline constexpr int kFormatVersion = 1;
/// Value of the root attribute `format`.
inline constexpr const char* kFormatName = "gesweep-archive";

inline constexpr const char* kRunsGroup = "runs";
inline constexpr const char* kRunIndex = "runs/index";      ///< int64: the run's index in the design
inline constexpr const char* kRunId = "runs/id";            ///< uint64: hash of its design parameters
inline constexpr const char* kRunStatus = "runs/status";    ///< int8: 0 pending, 1 ok, 2 failed
inline constexpr const char* kRunMessage = "runs/message";  ///< fixed-length UTF-8 string
inline constexpr const char* kDesignGroup = "design";       ///< one float64 dataset per swept parameter
inline constexpr const char* kResultsGroup = "results";     ///< results/<analysis>/<name>
inline constexpr const char* kSeriesGroup = "series";       ///< series/<analysis>/time_s and N×T series
inline constexpr const char* kAnalysisGroup = "analysis";   ///< derived products (boundary, sensitivity, ...)

/// Path of the dataset of a design parameter.
inline std::string DesignPath(const std::string& parameter) {
  return std::string(kDesignGroup) + "/" + parameter;
}

/// Value of the root attribute `study_fingerprint`: the study's fingerprint as 16 lowercase hex
/// digits (written by the writer, compared by the reader when a sweep resumes).
inline std::string FingerprintText(std::uint64_t fingerprint) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text(16, '0');
  for (int i = 15; i >= 0; --i, fingerprint >>= 4)
    text[static_cast<std::size_t>(i)] = kDigits[fingerprint & 0xf];
  return text;
}

}  // namespace gesweep::archive
