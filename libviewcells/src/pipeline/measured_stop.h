#pragma once
// AGVS stopped by measured frames (pipeline/pvs.cpp), shared by `pvs` and `bake`. Private to the
// library.
#include <functional>
#include <vector>

#include "viewcells/pipeline/pvs.h"

namespace viewcells::pipeline {

/// What measures a solver's PVSs part-way through a run: the scene it samples, its caster,
/// the cameras (each with its view cell among the solver's cells) and their frames.
struct SolverMeasuring {
  const Scene& scene;
  const RayCaster& caster;
  const CameraSet& cameras;
  FrameConfig frame;
};

/// The solver's PVSs now, measured by the cameras (logged).
MeasuredPoint measure_solver(const SolverMeasuring& m, const AgvsSolver& solver, const Log& log);

/// The stopping rule by measured error: the solver run to one batch, then to every doubling
/// of its samples, and measured each time (appended to `curve`, logged with an estimate of the
/// time left), until the cameras meet `target` (the mean wrong pixels, the paper's pixel error
/// that the estimator estimates, and/or the share of frames with holes), or one of `limits`'
/// own limits (samples, seconds, estimated error) stops it first. `after_run`, when given, is
/// called after each run, before measuring (a checkpoint). Returns whether the target stopped it.
bool run_to_measured_error(AgvsSolver& solver, const AgvsConfig& limits, const MeasuredTarget& target,
                           const SolverMeasuring& m, std::vector<MeasuredPoint>& curve, const Log& log,
                           const std::function<void()>& after_run = {});

}  // namespace viewcells::pipeline
