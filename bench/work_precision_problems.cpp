// The problems of the work-precision study: the fc3d and lcp problem files of the shared
// problem folder, the scene problems generated in-process (scene_problems.h) and the steps
// of MuJoCo's models (work_precision_mujoco.cpp).
#include "scene_problems.h"
#include "work_precision.h"

#include "lcp_contact_solver/core/problem_io.h"
#include "lcp_contact_solver/core/stabilization.h"

#include <dirent.h>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;

namespace lcs_bench {

bool isFc3d(const lcs::core::Problem& problem) {
  if (problem.contacts.empty()) return false;
  for (const lcs::core::Contact& c : problem.contacts)
    if (c.type != lcs::core::ContactType::kFrictional || c.rows != 3) return false;
  return true;
}

bool isLcp(const lcs::core::Problem& problem) {
  if (problem.contacts.empty()) return false;
  for (const lcs::core::Contact& c : problem.contacts)
    if (c.type != lcs::core::ContactType::kFrictionless) return false;
  return true;
}

}  // namespace lcs_bench

namespace lcs_bench::work_precision {

namespace {

std::vector<std::string> listDir(const std::string& dir) {
  std::vector<std::string> files;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n == "." || n == ".." || n == "README.md") continue;
      files.push_back(dir + "/" + n);
    }
    closedir(d);
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string baseName(const std::string& path) {
  std::string n = path.substr(path.find_last_of('/') + 1);
  for (const char* ext : {".hdf5.dat", ".dat", ".hdf5"})
    if (n.size() > std::strlen(ext) && n.compare(n.size() - std::strlen(ext), std::string::npos, ext) == 0) {
      n.resize(n.size() - std::strlen(ext));
      break;
    }
  return n;
}

void addProblemFiles(const Options& opt, std::vector<BenchProblem>* out) {
  for (const std::string family : {"fc3d", "lcp"}) {
    if (!opt.families.count(family)) continue;
    for (const std::string& path : listDir(opt.problems_dir + "/" + family)) {
      if (!opt.filter.empty() && path.find(opt.filter) == std::string::npos) continue;
      BenchProblem bp;
      bp.family = family;
      bp.name = baseName(path);
      try {
        bp.problem = lcs::core::readProblemFile(path);
      } catch (const std::exception& e) {
        std::cerr << "skipping " << path << ": " << e.what() << "\n";
        continue;
      }
      out->push_back(std::move(bp));
    }
  }
}

// A scene's contacts carry erp and depth, which our solvers apply before solving and the peers
// and the recomputed residual would not: folded into d_free once here, every solver and the
// check see the same problem (before, the core's residual and the recomputed one differed by
// up to 4e-8 relative on box pyramids and sphere piles).
void foldStabilization(lcs::core::Problem* problem) {
  const std::string error = lcs::core::applyStabilization(lcs::core::SolverParams{}, problem);
  if (!error.empty()) throw std::runtime_error(problem->name + ": " + error);
  for (lcs::core::Contact& c : problem->contacts) {
    c.erp = 0.0;
    c.softness = 0.0;
  }
}

void addSceneProblems(const Options& opt, std::vector<BenchProblem>* out) {
  if (opt.families.count("scenes")) {
    const auto t0 = Clock::now();
    for (lcs_bench::SceneProblem& sp :
         lcs_bench::makeSceneProblems(opt.scenes_dir, opt.pyramid_bases, opt.pile_balls, opt.scene_steps)) {
      if (!opt.filter.empty() && sp.name.find(opt.filter) == std::string::npos) continue;
      BenchProblem bp;
      bp.family = "scenes";
      bp.name = sp.name;
      bp.problem = std::move(sp.problem);
      foldStabilization(&bp.problem);
      double min_dn = std::numeric_limits<double>::infinity();
      const std::vector<int> off = bp.problem.rowOffsets();
      for (std::size_t c = 0; c < bp.problem.contacts.size(); ++c)
        min_dn = std::min(min_dn, bp.problem.d_free[off[c]]);
      std::cerr << "scene problem " << bp.name << ": " << sp.bodies << " bodies, "
                << bp.problem.contacts.size() << " contacts, " << bp.problem.rowCount() << " rows after "
                << sp.steps << " steps, min normal d_free " << min_dn << " m\n";
      out->push_back(std::move(bp));
    }
    std::cerr << "scene problems generated in " << std::chrono::duration<double>(Clock::now() - t0).count()
              << " s\n";
  }
}

}  // namespace

std::vector<BenchProblem> loadProblems(const Options& opt) {
  std::vector<BenchProblem> out;
  addProblemFiles(opt, &out);
  addSceneProblems(opt, &out);
  addMujocoProblems(opt, &out);
  return out;
}

}  // namespace lcs_bench::work_precision
