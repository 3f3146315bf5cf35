#pragma once
// The parts the pipeline's JSON reports share (report.cpp, report_runs.cpp; defined in
// report_parts.cpp): scene, sampling, subdivision, merge, measurement and AGVS summaries.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "viewcells/pipeline/report.h"

namespace viewcells::pipeline::report_detail {

using nlohmann::json;

json to_json(const Vec3& v);

json to_json(const Box3& b);

/// NaN (not known) as JSON null.
json number_or_null(double v);

json effect(bool enabled, const std::string& reason);

/// Reports say which Embree ISA cast their rays: results are bit-identical only for the same one.
/// On several MPI ranks they also say how many, and what the ranks exchanged (rank 0's side).
std::string text(json j);

json scene_summary(const Scene& s);

json sampling_effects(const SamplingRun& s);

json sampling_counts(const SamplingRun& s);

/// What sample and build share: the scene, sampling settings, effects, counts and timings.
json sampling_report(const SamplingRun& s);

json cost_curve(const Subdivision& sub);

json starts_json(const std::vector<MergeStart>& starts);

json chain_json(const MergeSummary& v);

json merge_summary(const MergeHistory& h);

json build_effects(const BuildResult& r);

json measure_json(const std::optional<PixelErrorMeasure>& m, uint32_t size);

json measured_curve(const std::vector<MeasuredPoint>& curve);

json agvs_distributions(const AgvsStats& st);

json agvs_curve(const AgvsStats& st, size_t references);

json agvs_view_space(bool restricted, bool play = false);

json pvs_effects(const PvsResult& r);

}  // namespace viewcells::pipeline::report_detail
