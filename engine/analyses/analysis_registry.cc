// The analyses a study can name, in the order their columns appear in an archive.
#include "engine/analyses/analysis_adapters.h"

namespace gesweep {

const std::vector<AnalysisEntry>& AnalysisRegistry() {
  static const std::vector<AnalysisEntry> registry = {
      {"modes", "eigenvalues, modes and stability margin at the run's height and speed", true,
       &MakeModesAnalysis, ""},
      {"flying_qualities", "MIL-F-8785C Category C levels of the short period and phugoid", true,
       &MakeFlyingQualitiesAnalysis, ""},
      {"boundary", "the stability boundary H* of the run's model at its speed", true, &MakeBoundaryAnalysis,
       ""},
      {"open_loop", "the time response to an elevator pulse", true, &MakeOpenLoopAnalysis, ""},
      {"landing", "the closed-loop landing: glide slope and flare", true, &MakeLandingAnalysis, ""},
      {"ishigami", "verification model: the Ishigami function of x1..x3", false, &MakeIshigamiAnalysis, ""},
      {"linear", "verification model: a linear function of x1..x8", false, &MakeLinearAnalysis, ""},
  };
  return registry;
}

}  // namespace gesweep
