#pragma once
/// Where `gesweep report` finds the Python that draws the report (scripts/report/report.py) and the
/// interpreter to run it with (docs/report.md, "gesweep report").

#include <filesystem>
#include <string>

namespace gesweep {

/// The report script: $GESWEEP_REPORT_SCRIPT when set, else scripts/report/report.py of the source
/// tree this engine was built from.
std::filesystem::path ReportScriptPath();

/// The interpreter: $GESWEEP_PYTHON when set, else /usr/bin/python3 (Debian's, which has h5py and
/// matplotlib; the python3 first on PATH may not).
std::string ReportPython();

}  // namespace gesweep
