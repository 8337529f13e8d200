// The bench's outputs: bench.csv (benchCsvColumns, one row a point; an error that was not
// measured is an empty cell), bench.json (everything, with each point's runs), bench.png
// (gnuplot: wall time against relative RMSE on log axes, lightmap, image and lightmap-lit
// image, each method's Pareto front drawn as a line), heatmaps/ (per-texel / per-pixel
// relative error, EXR and a colour PNG, for the VCT default and each other method's point
// nearest its error) and bench.md (a README-ready section embedding them, with the headline
// figures: the VCT default's lightmap, image and lightmap-lit image against each other method
// at equal error). With the stage
// scaling (scaling.h), bench.json has "scaling" and bench.md "How the stages scale". They
// name files as displayPath does (display_path.h): never by this machine's absolute paths.
#pragma once

#include "bench/run.h"

#include <string>
#include <utility>
#include <vector>

namespace vl {

const std::vector<std::string>& benchCsvColumns();

// (seconds, error) points of one method. Seconds to reach `error`, interpolated on log-log
// axes along the method's Pareto front; below its best error, extrapolated as error ∝ 1/√time
// (a Monte Carlo method's rate); above its worst, its fastest time (it is at least that good).
struct Reach {
    bool found = false;
    double seconds = 0.0;
    std::string how;  // "interpolated", "extrapolated (error ∝ 1/√time)", "at most (its fastest point)"
};
Reach timeToReach(std::vector<std::pair<double, double>> timeError, double error);
// The method's error at `seconds`, the same way round.
Reach errorAtTime(std::vector<std::pair<double, double>> timeError, double seconds);

// Indices of the points on the Pareto front (no other point at most as slow and at most as
// wrong, one strictly), in increasing time.
std::vector<size_t> paretoFront(const std::vector<std::pair<double, double>>& timeError);

// Writes every output into result.outputDir (adding their names to result.files) and prints
// the table on stdout (unless options.quiet).
void writeBenchOutputs(BenchResult& result, const BenchOptions& options);

}  // namespace vl
