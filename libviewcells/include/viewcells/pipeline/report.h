#pragma once
/// The one module that writes the pipeline's JSON reports: settings, the effects enabled and
/// why, counts, costs and timings, from the typed results of pipeline/*.h. Every report
/// records the Embree ISA that cast its rays (results are bit-identical only for the same).
#include <string>

#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/build.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/info.h"
#include "viewcells/pipeline/measure.h"
#include "viewcells/pipeline/pvs.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::pipeline {

/// The JSON text (indented, with a final newline) of each report.
std::string report_json(const SceneInfo& info);
std::string report_json(const SampleResult& result);
std::string report_json(const BuildResult& result);
std::string report_json(const ExtractResult& result);
std::string report_json(const CompressResult& result);
std::string report_json(const PvsResult& result);
std::string report_json(const BakeResult& result);
std::string report_json(const MeasureResult& result);

/// The cell and PVS of a point as `viewcells query --json` prints it.
std::string query_json(const PvsFile& file, const Vec3& point, int32_t cell);

/// Writes report_json(result) to path (atomically).
template <class Result>
void write_report(const std::string& path, const Result& result);

}  // namespace viewcells::pipeline
