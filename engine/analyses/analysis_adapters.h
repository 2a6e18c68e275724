#pragma once
/// Factories of the analysis adapters (one file each, engine/analyses/*_analysis.cc); the registry
/// (analysis_registry.cc) lists them. Adding an analysis: write its adapter file, declare its
/// factory here, add one line to the registry (docs/sweep.md, "Adding an analysis").

#include <memory>

#include "engine/analyses/analysis.h"

namespace gesweep {

/// `modes`: AnalyzeModes(model.StateMatrix(H, u0)) per run (docs/model.md §6).
std::unique_ptr<Analysis> MakeModesAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `flying_qualities`: MIL-F-8785C levels of AnalyzeModes(model.StateMatrix(H, u0)) (docs/model.md §11).
std::unique_ptr<Analysis> MakeFlyingQualitiesAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `boundary`: FindBoundary(model, u0) per run (docs/model.md §6).
std::unique_ptr<Analysis> MakeBoundaryAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `ishigami`: the Ishigami function of x1..x3 (verification).
std::unique_ptr<Analysis> MakeIshigamiAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `linear`: intercept + Σ cᵢ xᵢ (verification).
std::unique_ptr<Analysis> MakeLinearAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `open_loop`: the time response to an elevator pulse (docs/model.md §7).
std::unique_ptr<Analysis> MakeOpenLoopAnalysis(const TomlSection& settings, const Aircraft* aircraft);
/// `landing`: the closed-loop glide slope and flare (docs/model.md §8).
std::unique_ptr<Analysis> MakeLandingAnalysis(const TomlSection& settings, const Aircraft* aircraft);

}  // namespace gesweep
