#include "engine/cli/report_script.h"

#include <cstdlib>

namespace gesweep {

std::filesystem::path ReportScriptPath() {
  if (const char* path = std::getenv("GESWEEP_REPORT_SCRIPT"); path != nullptr && *path != '\0') return path;
  return GESWEEP_REPORT_SCRIPT_DEFAULT;
}

std::string ReportPython() {
  if (const char* python = std::getenv("GESWEEP_PYTHON"); python != nullptr && *python != '\0') return python;
  return "/usr/bin/python3";
}

}  // namespace gesweep
