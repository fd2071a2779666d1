// The "auto regret" table of the work-precision study (markdown, --regret): per problem and
// tolerance, auto's time over the fastest of our other solvers and over the fastest peer
// that reached the same residual.
#pragma once

#include "work_precision.h"

#include <vector>

namespace lcs_bench::work_precision {

// Writes the table for these rows to opt.regret (a message on stderr when it cannot).
void writeRegret(const Options& opt, const std::vector<Row>& rows);

}  // namespace lcs_bench::work_precision
