#include "engine/simulation/lanes_isa.h"

#include <cstdlib>

#include "engine/common/errors.h"

namespace gesweep {

int LanesIsaVectorWidth(LanesIsa isa) {
  switch (isa) {
    case LanesIsa::kSse2:
      return 2;
    case LanesIsa::kAvx2:
      return 4;
    case LanesIsa::kAvx512:
      return 8;
  }
  GESWEEP_UNREACHABLE();
}

bool LanesIsaSupported(LanesIsa isa) {
  // GCC's and Clang's CPU model (libgcc, compiler-rt) checks the CPUID bits and, through XGETBV, that
  // the operating system saves the YMM and ZMM registers. (xsimd 8.1's available_architectures()
  // reads the CPUID bits only.)
  switch (isa) {
    case LanesIsa::kSse2:
      return true;  // x86-64
    case LanesIsa::kAvx2:
      return __builtin_cpu_supports("avx2");
    case LanesIsa::kAvx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl");
  }
  GESWEEP_UNREACHABLE();
}

std::vector<LanesIsa> SupportedLanesIsas() {
  std::vector<LanesIsa> supported;
  for (const auto& entry : EnumNames<LanesIsa>::kTable) {
    if (LanesIsaSupported(entry.value)) supported.push_back(entry.value);
  }
  return supported;
}

LanesIsa ChooseLanesIsa(int width) {
  const char* forced = std::getenv(kLanesIsaVariable);
  if (forced != nullptr && *forced != '\0') {
    const std::optional<LanesIsa> isa = ParseEnum<LanesIsa>(forced);
    if (!isa) {
      throw InputError("environment", kLanesIsaVariable, EscapeForMessage(forced),
                       "expected " + EnumChoices<LanesIsa>() + " (or unset: chosen by the CPU)");
    }
    if (!LanesIsaSupported(*isa)) {
      std::string supported;
      for (LanesIsa s : SupportedLanesIsas())
        supported += (supported.empty() ? "" : ", ") + std::string(ToString(s));
      throw InputError("environment", kLanesIsaVariable, EscapeForMessage(forced),
                       "expected an instruction set this CPU runs: " + supported);
    }
    return *isa;
  }
  LanesIsa best = LanesIsa::kSse2;
  for (LanesIsa isa : SupportedLanesIsas()) {
    if (LanesIsaVectorWidth(isa) <= width) best = isa;
  }
  return best;
}

}  // namespace gesweep
