// The `mujoco` family of the work-precision study: the constraint problems of steps of
// MuJoCo's own shipped models (libmujoco-samples), through the package's MuJoCo adapter
// (mujoco_adapter.h), so auto is judged on problems no threshold of it was set on.
//
// Each model runs its trajectory with MuJoCo's own default solver from the model's initial
// state (the same reference trajectory as bench/mujoco_bench.cpp); the problems of the
// wanted steps are taken, once with the pyramidal cone (an LCP: W = efc_AR positive
// definite, one unilateral row per pyramid edge, limits, bilateral equalities) and once with
// the elliptic cone (Coulomb disc contacts). W is dense up to 200 rows, block-sparse above
// (the adapter's automatic storage, the bridge's default).
#include "work_precision.h"

#include "lcp_contact_solver/scene/mujoco_adapter.h"
#include "lcp_contact_solver/scene/mujoco_world.h"

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

namespace lcs_bench::work_precision {

namespace {

std::string modelName(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  return name.substr(0, name.find_last_of('.'));
}

bool hasFrictionalContact(const lcs::core::Problem& problem) {
  for (const lcs::core::Contact& c : problem.contacts)
    if (c.type == lcs::core::ContactType::kFrictional) return true;
  return false;
}

// The problems of the wanted steps of one model under one cone; a model that does not load
// or step is reported and skipped.
void addModelSteps(const Options& opt, const std::string& path, const std::string& cone,
                   std::vector<BenchProblem>* out) {
  namespace sc = lcs::scene;
  sc::MujocoOptions mo;
  mo.cone = cone;
  std::string error;
  auto world = sc::MujocoWorld::load(path, mo, &error);
  if (!world) {
    std::cerr << "skipping " << path << ": " << error << "\n";
    return;
  }
  const int last = *std::max_element(opt.mujoco_steps.begin(), opt.mujoco_steps.end());
  auto scratch = world->clone();
  for (int step = 0; step <= last; ++step) {
    if (std::find(opt.mujoco_steps.begin(), opt.mujoco_steps.end(), step) != opt.mujoco_steps.end()) {
      scratch->copyDataFrom(*world);
      sc::forwardToConstraints(scratch->model(), scratch->data(), false);
      sc::MujocoProblem mp;
      error = sc::extractProblem(scratch->model(), scratch->data(), sc::MujocoExtractOptions{}, &mp);
      const std::string name = modelName(path) + "_" + cone + "_s" + std::to_string(step);
      if (!error.empty()) {
        std::cerr << "skipping " << name << ": " << error << "\n";
      } else if (mp.problem.contacts.empty()) {
        std::cerr << "skipping " << name << ": no constraint rows\n";
      } else if (cone == "elliptic" && !hasFrictionalContact(mp.problem)) {
        std::cerr << "skipping " << name << ": no frictional contact (the pyramidal problem's rows)\n";
      } else if (opt.filter.empty() || name.find(opt.filter) != std::string::npos) {
        std::cerr << "mujoco problem " << name << ": " << mp.ncon << " MuJoCo contacts, "
                  << mp.problem.contacts.size() << " entries, " << mp.problem.rowCount() << " rows\n";
        BenchProblem bp;
        bp.family = "mujoco";
        bp.name = name;
        bp.problem = std::move(mp.problem);
        out->push_back(std::move(bp));
      }
    }
    sc::forwardToConstraints(world->model(), world->data(), true);
    error = sc::integrateEuler(world->model(), world->data());
    if (!error.empty()) {
      std::cerr << "skipping the rest of " << path << ": " << error << "\n";
      return;
    }
  }
}

}  // namespace

void addMujocoProblems(const Options& opt, std::vector<BenchProblem>* out) {
  if (!opt.families.count("mujoco") || opt.mujoco_steps.empty()) return;
  for (const std::string& model : opt.mujoco_models)
    for (const char* cone : {"pyramidal", "elliptic"}) addModelSteps(opt, model, cone, out);
}

}  // namespace lcs_bench::work_precision
