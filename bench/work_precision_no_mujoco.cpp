// Without libmujoco-dev the study has no mujoco family: its problems are left out, said once.
#include "work_precision.h"

#include <iostream>

namespace lcs_bench::work_precision {

void addMujocoProblems(const Options& opt, std::vector<BenchProblem>*) {
  if (opt.families.count("mujoco")) std::cerr << "work_precision: built without MuJoCo; no mujoco family\n";
}

}  // namespace lcs_bench::work_precision
