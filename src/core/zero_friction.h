// μ = 0 contacts cost one row (docs/SOLVERS.md "Contact models"): a frictional contact whose
// μ is 0 has two tangent rows that can never carry force, so the kernels solve the problem
// without them and the result is expanded back to every row. Private to the core library.
#pragma once

#include "lcp_contact_solver/core/problem.h"

#include <vector>

namespace lcp_contact_solver::core {

// A frictional contact whose μ (or the default μ it takes) is 0.
bool zeroFriction(const Contact& c, double default_mu);

// The problem without those rows: each such contact becomes a 1-row frictionless one, W and
// d_free keep its normal row only. `kept` maps each reduced row to its row in the original.
struct Compaction {
  Problem reduced;
  std::vector<int> kept;
};

Compaction compactZeroFriction(const Problem& p, double default_mu);

}  // namespace lcp_contact_solver::core
