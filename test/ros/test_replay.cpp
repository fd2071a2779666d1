// The offline replay (no master): pairing, comparison, outputs and faults on bags written
// here through the node's own solve path (CycleSolver); the bags shipped in test/data:
//   - references from outside (mujoco_*.bag, scripts/record-mujoco-bags): MuJoCo's own
//     efc_force recorded beside the problems; our replay must match it (the correctness check);
//   - change detectors (the others, scripts/record-bags): our own earlier output, which the
//     replay must reproduce (equal by construction while the code is unchanged, so they only
//     detect change), each beside an independent check of every recorded answer on its own
//     problem (answer_check.h: residual, states, signs, friction cone).
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/solver_param_table.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/answer_check.h"
#include "lcp_contact_solver/ros/replay/bag_replay.h"
#include "lcp_contact_solver/ros/replay/params_file.h"
#include "replay/replay_command.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver::Compliance;
using lcp_contact_solver::ConstraintForces;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::SolverStats;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

namespace {

fs::path tmpDir() {
  static const fs::path dir = [] {
    fs::path d = fs::path(LCS_TEST_TMP_DIR) / ("test_replay_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string tmpFile(const std::string& name) { return (tmpDir() / name).string(); }

// The bags and files written here go when the tests end.
class RemoveTmpDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(tmpDir(), ignored);
  }
};
const ::testing::Environment* const kRemoveTmpDir = ::testing::AddGlobalTestEnvironment(new RemoveTmpDir);

// How a synthetic recording is written.
struct Recording {
  int cycles = 12;
  std::string prefix = "/";          // topic namespace
  bool compliance_first_odd = true;  // odd cycles: compliance recorded before contacts
  int unpaired_cycle = -1;           // this cycle's compliance is missing
  double force_scale = 1.0;          // recorded forces = solved forces × this (perturbation)
  bool with_outputs = true;          // record forces and stats
  double reference_scale = 0.0;      // > 0: "reference_forces" = solved forces × this (from outside)
  bool block_sparse = false;
  lcs::core::SolverParams params = defaultSolverParams();
};

// The test scene with cycle-dependent d_free (so warm starts matter), solved in order by
// the node's CycleSolver, written as a live recording would be: contacts and compliance
// at t, the node's forces and stats a little later.
Scene cycleScene(int k, bool block_sparse) {
  const ros::Time stamp(100.0 + 0.01 * k);
  Scene s = makeScene(7000, stamp, block_sparse);
  for (auto& c : s.contacts.contacts)
    for (double& d : c.d_free) d *= 1.0 + 0.3 * std::sin(0.7 * k);
  return s;
}

void writeRecording(const std::string& path, const Recording& rec) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  CycleSolver solver(rec.params);
  for (int k = 0; k < rec.cycles; ++k) {
    const Scene s = cycleScene(k, rec.block_sparse);
    const ros::Time t(1000.0 + 0.01 * k);
    const ros::Duration us(0, 1000);
    const bool skip_compliance = k == rec.unpaired_cycle;
    if (rec.compliance_first_odd && k % 2 == 1) {
      if (!skip_compliance) bag.write(rec.prefix + "compliance", t, s.compliance);
      bag.write(rec.prefix + "contacts", t + us, s.contacts);
    } else {
      bag.write(rec.prefix + "contacts", t, s.contacts);
      if (!skip_compliance) bag.write(rec.prefix + "compliance", t + us, s.compliance);
    }
    if (skip_compliance || (!rec.with_outputs && rec.reference_scale <= 0.0)) continue;
    CycleOutput out = solver.solve(s.contacts, s.compliance);
    out.stats.forces_published = out.has_forces;
    if (rec.reference_scale > 0.0 && out.has_forces) {
      ConstraintForces reference = out.forces;
      for (auto& f : reference.forces)
        for (double& l : f.lambda) l *= rec.reference_scale;
      bag.write(rec.prefix + "reference_forces", t + us + us, reference);
    }
    if (!rec.with_outputs) continue;
    if (out.has_forces) {
      for (auto& f : out.forces.forces)
        for (double& l : f.lambda) l *= rec.force_scale;
      bag.write(rec.prefix + "constraint_forces", t + us + us, out.forces);
    }
    bag.write(rec.prefix + "contact_solver/stats", t + us + us, out.stats);
  }
  bag.close();
}

ReplayResult replayFile(const std::string& path,
                        const lcs::core::SolverParams& params = defaultSolverParams(),
                        ReplayOptions options = ReplayOptions()) {
  options.bag = path;
  options.keep_cycles = true;
  return replayBag(options, params);
}

int runCommand(const std::vector<std::string>& args, std::string* out_text = nullptr,
               std::string* err_text = nullptr) {
  std::ostringstream out, err;
  const int code = runReplayCommand(args, out, err);
  if (out_text) *out_text = out.str();
  if (err_text) *err_text = err.str();
  return code;
}

std::vector<std::string> readLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::size_t countMessages(const std::string& path, const std::string& topic) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  return view.size();
}

}  // namespace

// ---- the offline path against the live path's solve -------------------------------------

// The offline path is the live one (same CycleSolver, same order): bit-identical by
// construction. A check of the replay's plumbing, not of the forces' correctness (that is
// the reference comparison and the answer check below).
TEST(Replay, ReproducesTheRecordedForcesExactly) {
  const std::string bag = tmpFile("exact.bag");
  Recording rec;
  writeRecording(bag, rec);
  const ReplayResult r = replayFile(bag);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.contacts_topic, "/contacts");
  EXPECT_EQ(r.compliance_topic, "/compliance");
  EXPECT_EQ(r.forces_topic, "/constraint_forces");
  EXPECT_EQ(r.stats_topic, "/contact_solver/stats");
  EXPECT_EQ(r.cycles, 12u);
  EXPECT_EQ(r.solved, 12u);
  EXPECT_EQ(r.unpaired, 0u);
  EXPECT_EQ(r.comparison.compared, 12u);
  EXPECT_EQ(r.comparison.mismatched + r.comparison.missing_reference + r.comparison.missing_replay, 0u);
  EXPECT_EQ(r.comparison.max_abs, 0.0);  // same code, same inputs, same order: bit-identical
  EXPECT_EQ(r.comparison.max_relative, 0.0);
  EXPECT_EQ(r.comparison.stats_compared, 12u);
  EXPECT_EQ(r.comparison.iteration_differences, 0u);
  EXPECT_EQ(r.comparison.max_residual_relative, 0.0);
  EXPECT_FALSE(r.comparison.exceeds(0.0));
  ASSERT_EQ(r.cycles_kept.size(), 12u);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(r.cycles_kept[k].stamp, ros::Time(100.0 + 0.01 * k)) << k;
}

TEST(Replay, WarmStartCarriesAcrossCyclesAsInTheNode) {
  const std::string bag = tmpFile("warm.bag");
  writeRecording(bag, Recording());
  lcs::core::SolverParams cold = defaultSolverParams();
  ASSERT_EQ(applyReplayOverride("initial_guess=false", &cold), "");
  const ReplayResult r = replayFile(bag, cold);
  ASSERT_EQ(r.error, "");
  // Without the warm start the solver takes other paths: iteration counts change.
  EXPECT_GT(r.comparison.iteration_differences, 0u);
  EXPECT_EQ(r.comparison.compared, 12u);
  EXPECT_LE(r.comparison.max_relative, 1e-2);  // both converged to the same tolerance
  EXPECT_GT(r.comparison.max_relative, 0.0);
}

TEST(Replay, BlockSparseComplianceAndOtherParameters) {
  const std::string bag = tmpFile("sparse.bag");
  Recording rec;
  rec.block_sparse = true;
  ASSERT_EQ(applyReplayOverride("solver=pgs", &rec.params), "");
  ASSERT_EQ(applyReplayOverride("friction_model=pyramid4", &rec.params), "");
  ASSERT_EQ(applyReplayOverride("tolerance=1e-8", &rec.params), "");
  writeRecording(bag, rec);
  const ReplayResult same = replayFile(bag, rec.params);
  ASSERT_EQ(same.error, "");
  EXPECT_EQ(same.comparison.compared, 12u);
  EXPECT_EQ(same.comparison.max_relative, 0.0);
  const ReplayResult other = replayFile(bag, defaultSolverParams());  // nlgs on the disc
  ASSERT_EQ(other.error, "");
  EXPECT_TRUE(other.comparison.exceeds(1e-6));
}

// ---- pairing ---------------------------------------------------------------------------

TEST(Replay, PairsByStampInEitherOrderAndReportsUnpaired) {
  const std::string bag = tmpFile("unpaired.bag");
  Recording rec;
  rec.unpaired_cycle = 5;
  writeRecording(bag, rec);
  const std::string csv = tmpFile("unpaired.csv");
  ReplayOptions options;
  options.csv = csv;
  const ReplayResult r = replayFile(bag, defaultSolverParams(), options);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.contact_messages, 12u);
  EXPECT_EQ(r.compliance_messages, 11u);
  EXPECT_EQ(r.cycles, 11u);
  EXPECT_EQ(r.unpaired, 1u);
  // The recording skipped the node's output for cycle 5 as well, so cycles after it were
  // warm-started from cycle 4 in both paths.
  EXPECT_EQ(r.comparison.compared, 11u);
  EXPECT_EQ(r.comparison.max_relative, 0.0);
  const std::vector<std::string> lines = readLines(csv);
  ASSERT_EQ(lines.size(), 13u);  // header, 11 cycles, 1 unpaired
  EXPECT_NE(lines.back().find("no_compliance"), std::string::npos);
}

TEST(StampPairer, ExactTimeSemantics) {
  StampPairer pairer;
  StampPairer::Pair pair;
  auto contacts = [](double t) {
    auto m = boost::make_shared<ContactArray>();
    m->header.stamp = ros::Time(t);
    return ContactArray::ConstPtr(m);
  };
  auto compliance = [](double t) {
    auto m = boost::make_shared<Compliance>();
    m->header.stamp = ros::Time(t);
    return Compliance::ConstPtr(m);
  };
  EXPECT_FALSE(pairer.addContacts(contacts(1.0), &pair));
  EXPECT_FALSE(pairer.addCompliance(compliance(2.0), &pair));
  EXPECT_TRUE(pairer.addContacts(contacts(2.0), &pair));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(2.0));
  EXPECT_EQ(pair.compliance->header.stamp, ros::Time(2.0));
  EXPECT_TRUE(pairer.addCompliance(compliance(1.0), &pair));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(1.0));
  EXPECT_FALSE(pairer.addContacts(contacts(3.0), &pair));
  EXPECT_FALSE(pairer.addContacts(contacts(3.0), &pair));
  EXPECT_EQ(pairer.duplicates(), 1u);
  EXPECT_EQ(pairer.waitingContacts().size(), 1u);
  EXPECT_EQ(pairer.waitingCompliance(), 0u);
}

// ---- topics ----------------------------------------------------------------------------

TEST(Replay, FindsNamespacedTopicsByTypeOrByOption) {
  const std::string bag = tmpFile("namespaced.bag");
  Recording rec;
  rec.prefix = "/sim/";
  writeRecording(bag, rec);
  const ReplayResult found = replayFile(bag);
  ASSERT_EQ(found.error, "");
  EXPECT_EQ(found.contacts_topic, "/sim/contacts");
  EXPECT_EQ(found.forces_topic, "/sim/constraint_forces");
  EXPECT_EQ(found.comparison.compared, 12u);
  EXPECT_EQ(found.comparison.max_relative, 0.0);
  EXPECT_FALSE(found.notes.empty());

  ReplayOptions options;
  options.contacts_topic = "sim/contacts";  // leading slash optional
  options.compliance_topic = "/sim/compliance";
  EXPECT_EQ(replayFile(bag, defaultSolverParams(), options).error, "");
  options.contacts_topic = "/other/contacts";
  const ReplayResult missing = replayFile(bag, defaultSolverParams(), options);
  EXPECT_NE(missing.error.find("no topic /other/contacts"), std::string::npos) << missing.error;
  options = ReplayOptions();
  options.contacts_topic = "/sim/compliance";  // wrong type
  const ReplayResult wrong = replayFile(bag, defaultSolverParams(), options);
  EXPECT_NE(wrong.error.find("not lcp_contact_solver/ContactArray"), std::string::npos) << wrong.error;
}

TEST(Replay, AmbiguousOrMissingInputTopicsAreErrors) {
  const std::string two = tmpFile("two.bag");
  {
    rosbag::Bag bag(two, rosbag::bagmode::Write);
    const Scene s = cycleScene(0, false);
    bag.write("/a/contacts", ros::Time(1.0), s.contacts);
    bag.write("/b/contacts", ros::Time(1.0), s.contacts);
    bag.write("/a/compliance", ros::Time(1.0), s.compliance);
  }
  const ReplayResult r = replayFile(two);
  EXPECT_NE(r.error.find("several lcp_contact_solver/ContactArray topics"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("--contacts-topic"), std::string::npos) << r.error;

  const std::string none = tmpFile("none.bag");
  {
    rosbag::Bag bag(none, rosbag::bagmode::Write);
    bag.write("/compliance", ros::Time(1.0), cycleScene(0, false).compliance);
  }
  const ReplayResult n = replayFile(none);
  EXPECT_NE(n.error.find("no lcp_contact_solver/ContactArray topic"), std::string::npos) << n.error;
}

// ---- comparison ------------------------------------------------------------------------

TEST(Replay, ComparisonMeasuresRelativeDifferences) {
  const std::string bag = tmpFile("perturbed.bag");
  Recording rec;
  rec.force_scale = 1.0 + 1e-6;
  writeRecording(bag, rec);
  const ReplayResult r = replayFile(bag);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.comparison.compared, 12u);
  EXPECT_NEAR(r.comparison.max_relative, 1e-6, 1e-9);
  EXPECT_GT(r.comparison.max_abs, 0.0);
  EXPECT_GT(r.comparison.rms(), 0.0);
  EXPECT_LE(r.comparison.rms(), r.comparison.max_abs);
  EXPECT_GE(r.comparison.worst_cycle, 0);
  EXPECT_TRUE(r.comparison.exceeds(1e-9));
  EXPECT_FALSE(r.comparison.exceeds(1e-5));

  std::string out;
  EXPECT_EQ(runCommand({bag, "--no-params-file", "--tolerance-compare", "1e-9"}, &out), 1) << out;
  EXPECT_NE(out.find("FAIL"), std::string::npos) << out;
  EXPECT_EQ(runCommand({bag, "--no-params-file", "--tolerance-compare=1e-5"}, &out), 0) << out;
  EXPECT_NE(out.find("OK"), std::string::npos) << out;
  EXPECT_NE(out.find("max |dlambda|"), std::string::npos) << out;
  EXPECT_NE(out.find("worst cycle #"), std::string::npos) << out;
}

TEST(CompareForces, StructureMismatchIsNeverWithinTolerance) {
  ConstraintForces a, b;
  a.forces.resize(2);
  b.forces.resize(1);
  EXPECT_NE(compareForces(a, b).mismatch, "");
  EXPECT_TRUE(std::isinf(compareForces(a, b).relative));
  b.forces.resize(2);
  a.forces[0].lambda = {1.0, 0.5, 0.0};
  b.forces[0].lambda = {1.0, 0.5};
  EXPECT_NE(compareForces(a, b).mismatch, "");
  b.forces[0].lambda = {1.0, 0.5, 0.0};
  b.forces[1].id = 4;
  EXPECT_NE(compareForces(a, b).mismatch, "");
  b.forces[1].id = 0;
  b.forces[0].lambda = {2.0, 0.5, 0.0};
  const ForceDifference d = compareForces(a, b);
  EXPECT_EQ(d.mismatch, "");
  EXPECT_DOUBLE_EQ(d.max_abs, 1.0);
  EXPECT_DOUBLE_EQ(d.relative, 0.5);
  EXPECT_EQ(compareForces(ConstraintForces(), ConstraintForces()).relative, 0.0);
}

TEST(Replay, NoRecordedForcesMeansNothingToCompare) {
  const std::string bag = tmpFile("inputs_only.bag");
  Recording rec;
  rec.with_outputs = false;
  writeRecording(bag, rec);
  const ReplayResult r = replayFile(bag);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.cycles, 12u);
  EXPECT_EQ(r.forces_topic, "");
  EXPECT_FALSE(r.comparison.hasReference());
  std::string out;
  EXPECT_EQ(runCommand({bag, "--no-params-file"}, &out), 0) << out;
  EXPECT_EQ(runCommand({bag, "--no-params-file", "--tolerance-compare", "1"}, &out), 1) << out;
  EXPECT_NE(out.find("no recorded forces"), std::string::npos) << out;
}

// ---- outputs ---------------------------------------------------------------------------

TEST(Replay, WritesOutputBagCsvAndParameters) {
  const std::string bag = tmpFile("outputs_in.bag");
  writeRecording(bag, Recording());
  const std::string out_bag = tmpFile("outputs_out.bag"), csv = tmpFile("outputs.csv");
  std::string out, err;
  ASSERT_EQ(runCommand({bag, "--no-params-file", "--out", out_bag, "--csv", csv, "maxIt=3", "--no-progress"},
                       &out, &err),
            0)
      << out << err;
  // Forces and stats under the recorded names with the contacts' stamps; inputs copied.
  EXPECT_EQ(countMessages(out_bag, "/constraint_forces"), 12u);
  EXPECT_EQ(countMessages(out_bag, "/contact_solver/stats"), 12u);
  EXPECT_EQ(countMessages(out_bag, "/contacts"), 12u);
  EXPECT_EQ(countMessages(out_bag, "/compliance"), 12u);
  {
    rosbag::Bag b(out_bag, rosbag::bagmode::Read);
    int k = 0;
    for (const rosbag::MessageInstance& m : rosbag::View(b, rosbag::TopicQuery("/constraint_forces"))) {
      const ConstraintForces::ConstPtr f = m.instantiate<ConstraintForces>();
      ASSERT_TRUE(f != nullptr);
      EXPECT_EQ(f->header.stamp, ros::Time(100.0 + 0.01 * k));
      EXPECT_EQ(f->header.frame_id, "world");
      EXPECT_EQ(f->forces.size(), 4u);
      ++k;
    }
    for (const rosbag::MessageInstance& m : rosbag::View(b, rosbag::TopicQuery("/contact_solver/stats"))) {
      const SolverStats::ConstPtr s = m.instantiate<SolverStats>();
      ASSERT_TRUE(s != nullptr);
      EXPECT_LE(s->iterations, 3);
      EXPECT_TRUE(s->forces_published);
    }
  }
  // The parameters beside it, and the output bag is itself a recording: replaying it with
  // those parameters reproduces it exactly.
  lcs::core::SolverParams written = defaultSolverParams();
  ASSERT_EQ(loadParamsFile(paramsFileBeside(out_bag), &written), "");
  EXPECT_EQ(written.maxIt, 3);
  EXPECT_EQ(runCommand({out_bag, "--tolerance-compare", "0"}, &out), 0) << out;
  EXPECT_NE(out.find(paramsFileBeside(out_bag)), std::string::npos) << out;

  const std::vector<std::string> lines = readLines(csv);
  ASSERT_EQ(lines.size(), 13u);
  EXPECT_EQ(lines[0], "stamp,contacts,rows,iterations,residual,converged,status,solve_time");
  EXPECT_EQ(lines[1].rfind("100.000000000,4,9,", 0), 0u) << lines[1];
  for (std::size_t i = 1; i < lines.size(); ++i)
    EXPECT_EQ(std::count(lines[i].begin(), lines[i].end(), ','), 7) << lines[i];
}

TEST(Replay, RefusesToOverwriteItsInput) {
  const std::string bag = tmpFile("self.bag");
  writeRecording(bag, Recording());
  std::string out, err;
  EXPECT_EQ(runCommand({bag, "--out", bag}, &out, &err), 2);
  EXPECT_NE(err.find("overwrite"), std::string::npos) << err;
  EXPECT_EQ(countMessages(bag, "/contacts"), 12u);
}

// ---- parameters ------------------------------------------------------------------------

TEST(ReplayParams, ShippedDefaultsFileIsTheNodeDefaults) {
  lcs::core::SolverParams p = defaultSolverParams();
  ASSERT_EQ(loadParamsFile(LCS_CONFIG_DIR "/default.yaml", &p), "");
  const lcs::core::SolverParams d = defaultSolverParams();
  EXPECT_EQ(p.tolerance, d.tolerance);
  EXPECT_EQ(p.maxIt, d.maxIt);
  EXPECT_EQ(p.mu, d.mu);
  EXPECT_EQ(p.initial_guess, d.initial_guess);
  EXPECT_EQ(p.max_rows, d.max_rows);
  EXPECT_EQ(p.solver, d.solver);
}

TEST(ReplayParams, RoundTripOverridesAndFaults) {
  lcs::core::SolverParams p = defaultSolverParams();
  for (const char* o : {"tolerance=1e-7", "maxIt=77", "mu=0.25", "initial_guess=false", "solver=apgd",
                        "stopping_rule=sofa", "sor=1.2", "regularizationTerm=1e-9", "max_rows=500", "erp=0.3",
                        "constraint_level=velocity", "time_step=0.01", "islands=false", "threads=2"})
    ASSERT_EQ(applyReplayOverride(o, &p), "") << o;
  const std::string path = tmpFile("round.params.yaml");
  ASSERT_EQ(writeParamsFile(path, p), "");
  lcs::core::SolverParams q = defaultSolverParams();
  ASSERT_EQ(loadParamsFile(path, &q), "");
  EXPECT_EQ(q.tolerance, 1e-7);
  EXPECT_EQ(q.maxIt, 77);
  EXPECT_EQ(q.mu, 0.25);
  EXPECT_FALSE(q.initial_guess);
  EXPECT_EQ(q.solver, lcs::core::SolverKind::kApgd);
  EXPECT_EQ(q.stopping_rule, lcs::core::StoppingRule::kSofa);
  EXPECT_EQ(q.sor, 1.2);
  EXPECT_EQ(q.regularizationTerm, 1e-9);
  EXPECT_EQ(q.max_rows, 500);
  // Every parameter of the table is written, so the file reproduces the solve exactly.
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    EXPECT_EQ(lcs::core::paramText(q, spec.name), lcs::core::paramText(p, spec.name)) << spec.name;

  EXPECT_NE(applyReplayOverride("initial_guess=maybe", &p), "");
  EXPECT_NE(applyReplayOverride("nosuch=1", &p), "");
  const std::string bad = tmpFile("bad.params.yaml");
  std::ofstream(bad) << "tolerance: 0.001\nfoo: 3\n";
  EXPECT_NE(loadParamsFile(bad, &q).find("unknown parameter 'foo'"), std::string::npos);
  std::ofstream(bad) << "maxIt: lots\n";
  EXPECT_NE(loadParamsFile(bad, &q).find("maxIt"), std::string::npos);
  std::ofstream(bad) << "tolerance: -1\n";
  EXPECT_NE(loadParamsFile(bad, &q).find("tolerance"), std::string::npos);
  std::ofstream(bad) << "[1, 2\n";
  EXPECT_NE(loadParamsFile(bad, &q), "");
  EXPECT_NE(loadParamsFile(tmpFile("missing.yaml"), &q), "");
  EXPECT_EQ(q.maxIt, 77);  // a refused file changes nothing
  EXPECT_EQ(paramsFileBeside("dir/box.bag"), "dir/box.params.yaml");
}

// ---- faults ----------------------------------------------------------------------------

TEST(Replay, MalformedOrMissingBagsGiveOneLineErrors) {
  const std::string garbage = tmpFile("garbage.bag");
  std::ofstream(garbage) << "this is not a bag\n";
  const std::string good = tmpFile("to_truncate.bag");
  writeRecording(good, Recording());
  const std::string truncated = tmpFile("truncated.bag");
  {
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  const std::string empty = tmpFile("empty.bag");
  std::ofstream(empty).close();
  for (const std::string& path :
       {garbage, truncated, empty, tmpFile("does_not_exist.bag"), tmpDir().string()}) {
    const ReplayResult r = replayFile(path);
    EXPECT_NE(r.error, "") << path;
    EXPECT_EQ(r.error.find('\n'), std::string::npos) << r.error;
    std::string out, err;
    EXPECT_EQ(runCommand({path, "--quiet"}, &out, &err), 2) << path;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_EQ(err.rfind("replay: ", 0), 0u) << err;
  }
}

TEST(ReplayCommand, UsageErrors) {
  std::string out, err;
  EXPECT_EQ(runCommand({}, &out, &err), 2);
  EXPECT_EQ(runCommand({"--help"}, &out, &err), 0);
  EXPECT_NE(out.find("--tolerance-compare"), std::string::npos);
  const std::string bag = tmpFile("usage.bag");
  writeRecording(bag, Recording());
  EXPECT_EQ(runCommand({bag, "--bogus"}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "maxIt=abc"}, &out, &err), 2);
  EXPECT_NE(err.find("maxIt"), std::string::npos) << err;
  EXPECT_EQ(runCommand({bag, "tolerance=-1"}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "second.bag"}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "--tolerance-compare", "x"}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "--tolerance-compare"}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "--params", tmpFile("nope.yaml")}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "--csv", tmpFile("no_dir/x.csv")}, &out, &err), 2);
  EXPECT_EQ(runCommand({bag, "--quiet"}, &out, &err), 0);
  EXPECT_EQ(out, "");
}

// ---- the shipped recordings ------------------------------------------------------------

// ---- a reference from outside ------------------------------------------------------------

TEST(ReferenceTopic, ComparedWithTheReferenceNotTheRecording) {
  const std::string bag = tmpFile("reference.bag");
  Recording rec;
  rec.reference_scale = 1.001;  // the outside solver disagrees by 1e-3
  writeRecording(bag, rec);
  ReplayOptions options;
  options.reference_topic = "reference_forces";  // leading '/' optional
  const ReplayResult r = replayFile(bag, defaultSolverParams(), options);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.forces_topic, "/constraint_forces");
  EXPECT_EQ(r.reference_topic, "/reference_forces");
  EXPECT_EQ(r.comparison.compared, 12u);
  EXPECT_EQ(r.comparison.max_relative, 0.0);  // the recording: reproduced
  EXPECT_EQ(r.reference.compared, 12u);
  EXPECT_NEAR(r.reference.max_relative, 0.001 / 1.001, 1e-12);
  ASSERT_EQ(r.reference_cycles.size(), 12u);
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(r.reference_cycles[k].cycle, static_cast<long>(k));
    EXPECT_EQ(r.reference_cycles[k].contacts, 4u);
    EXPECT_NEAR(r.reference_cycles[k].relative, 0.001 / 1.001, 1e-12) << k;
    EXPECT_GT(r.reference_cycles[k].max_abs, 0.0);
  }
  EXPECT_TRUE(r.reference.exceeds(1e-4));
  EXPECT_FALSE(r.reference.exceeds(1e-2));

  // The command judges the reference when given one, not the (reproduced) recording.
  std::string out;
  EXPECT_EQ(runCommand({bag, "--reference-topic", "/reference_forces", "--tolerance-compare", "1e-2",
                        "--per-cycle", "--no-progress"},
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("forces vs reference /reference_forces: 12 cycles compared"), std::string::npos) << out;
  EXPECT_NE(out.find("OK: forces match the reference /reference_forces within 0.01"), std::string::npos)
      << out;
  EXPECT_NE(out.find("\n11 100.110000000 4 "), std::string::npos) << out;  // --per-cycle: the last cycle
  EXPECT_EQ(runCommand({bag, "--reference-topic", "/reference_forces", "--tolerance-compare", "1e-4"}, &out),
            1);
  EXPECT_NE(
      out.find("FAIL: forces differ from the reference /reference_forces: max relative 0.000999 > 0.0001"),
      std::string::npos)
      << out;
  EXPECT_EQ(runCommand({bag, "--tolerance-compare", "1e-4"}, &out), 0) << out;  // without it: the recording
}

TEST(ReferenceTopic, NeverTakenAsTheRecordedOutputAndMustExist) {
  const std::string bag = tmpFile("reference_only.bag");
  Recording rec;
  rec.with_outputs = false;
  rec.reference_scale = 1.0;
  rec.unpaired_cycle = 4;  // no compliance, no reference: a reference stamp the replay lacks is counted
  writeRecording(bag, rec);
  ReplayOptions options;
  options.reference_topic = "/reference_forces";
  ReplayResult r = replayFile(bag, defaultSolverParams(), options);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.forces_topic, "");  // the only ConstraintForces topic is the reference
  EXPECT_EQ(r.reference.compared, 11u);
  EXPECT_EQ(r.reference.max_relative, 0.0);
  EXPECT_EQ(r.reference.missing_reference + r.reference.missing_replay + r.reference.mismatched, 0u);

  options.forces_topic = "/reference_forces";
  r = replayFile(bag, defaultSolverParams(), options);
  EXPECT_NE(r.error.find("cannot be both"), std::string::npos) << r.error;
  options.forces_topic.clear();
  options.reference_topic = "/mujoco_bridge/reference_forces";
  r = replayFile(bag, defaultSolverParams(), options);
  EXPECT_NE(r.error.find("no topic /mujoco_bridge/reference_forces in the bag"), std::string::npos)
      << r.error;
  EXPECT_EQ(runCommand({bag, "--reference-topic", "/contacts"}), 2);  // not ConstraintForces

  // A reference for a cycle the replay cannot compare: not within any tolerance.
  const std::string partial = tmpFile("reference_scaled.bag");
  rec.unpaired_cycle = -1;
  writeRecording(partial, rec);
  options.reference_topic = "/reference_forces";
  lcs::core::SolverParams failing = defaultSolverParams();
  failing.solver = lcs::core::SolverKind::kLemke;
  failing.maxIt = 1;  // Lemke's cap: no forces
  r = replayFile(partial, failing, options);
  ASSERT_EQ(r.error, "");
  EXPECT_GT(r.reference.missing_replay, 0u);
  EXPECT_TRUE(r.reference.exceeds(1.0));
}

// ---- the independent check of a recorded answer -------------------------------------------

// The index of the first contact of `type` with a positive normal force.
int pressedContact(const CycleOutput& out, lcs::core::ContactType type) {
  for (std::size_t i = 0; i < out.problem.contacts.size(); ++i)
    if (out.problem.contacts[i].type == type && out.forces.forces[i].lambda[0] > 1e-6)
      return static_cast<int>(i);
  return -1;
}

TEST(AnswerCheck, TheSolvedAnswerPassesEveryCorruptionFails) {
  lcs::core::SolverParams params = defaultSolverParams();
  params.tolerance = 1e-10;
  CycleSolver solver(params);
  const Scene scene = makeScene(9100, ros::Time(5.0));
  const CycleOutput out = solver.solve(scene.contacts, scene.compliance);
  ASSERT_TRUE(out.has_forces);
  ASSERT_TRUE(out.result.converged);
  const AnswerCheck good = checkAnswer(out.problem, params, out.forces);
  EXPECT_TRUE(good.invariantsHold()) << good.unfit << good.first_violation;
  EXPECT_TRUE(residualsAgree(good.residual, out.stats.residual))
      << good.residual << " " << out.stats.residual;
  EXPECT_LE(good.residual, params.tolerance);
  AnswerChecks all;
  EXPECT_TRUE(all.add(good, &out.stats, params, ros::Time(5.0)));
  EXPECT_TRUE(all.passed());

  const int frictional = pressedContact(out, lcs::core::ContactType::kFrictional);
  const int frictionless = pressedContact(out, lcs::core::ContactType::kFrictionless);
  ASSERT_GE(frictional, 0) << "the test scene should press a frictional contact";
  ASSERT_GE(frictionless, 0) << "the test scene should press a frictionless contact";
  auto judged = [&](const ConstraintForces& forces, AnswerCheck* check = nullptr) {
    const AnswerCheck c = checkAnswer(out.problem, params, forces);
    if (check) *check = c;
    AnswerChecks one;
    return one.add(c, &out.stats, params, ros::Time(5.0));
  };
  {  // a normal force 1e-4 off: the residual no longer is the recorded one, nor below the tolerance
    ConstraintForces f = out.forces;
    f.forces[frictional].lambda[0] *= 1.0001;
    AnswerCheck c;
    EXPECT_FALSE(judged(f, &c));
    EXPECT_GT(c.residual, params.tolerance);
    EXPECT_FALSE(residualsAgree(c.residual, out.stats.residual));
  }
  {  // a pulling frictionless contact
    ConstraintForces f = out.forces;
    f.forces[frictionless].lambda[0] = -f.forces[frictionless].lambda[0];
    AnswerCheck c;
    EXPECT_FALSE(judged(f, &c));
    EXPECT_EQ(c.negative_normals, 1u);
  }
  {  // friction beyond the cone
    ConstraintForces f = out.forces;
    const double mu = lcs::core::effectiveMu(out.problem, params.mu)[frictional];
    f.forces[frictional].lambda[1] = 2.0 * mu * f.forces[frictional].lambda[0];
    AnswerCheck c;
    EXPECT_FALSE(judged(f, &c));
    EXPECT_EQ(c.outside_cone, 1u) << c.first_violation;
  }
  {  // a state its force does not have
    ConstraintForces f = out.forces;
    f.forces[frictionless].state = lcp_contact_solver::ContactForce::OPEN;
    AnswerCheck c;
    EXPECT_FALSE(judged(f, &c));
    EXPECT_EQ(c.state_differences, 1u);
    EXPECT_NE(c.first_violation.find("recorded state 0"), std::string::npos) << c.first_violation;
  }
  {  // forces of other contacts
    ConstraintForces f = out.forces;
    f.forces[0].id += 1;
    AnswerCheck c;
    EXPECT_FALSE(judged(f, &c));
    EXPECT_NE(c.unfit, "");
  }
  {  // converged as recorded, but the stats claim a residual the forces do not have
    lcp_contact_solver::SolverStats stats = out.stats;
    stats.residual = 10.0 * params.tolerance;
    AnswerChecks one;
    EXPECT_FALSE(one.add(good, &stats, params, ros::Time(5.0)));
    EXPECT_EQ(one.residual_differs, 1u);
  }
}

TEST(AnswerCheck, ReplayFlagsARecordingWhoseForcesWereCorrupted) {
  lcs::core::SolverParams params = defaultSolverParams();
  params.tolerance = 1e-10;
  for (const double scale : {1.0, 1.0 + 1e-6}) {
    const std::string bag = tmpFile("answers.bag");
    Recording rec;
    rec.params = params;
    rec.force_scale = scale;
    writeRecording(bag, rec);
    ReplayOptions options;
    options.recorded_params = params;
    const ReplayResult r = replayFile(bag, params, options);
    ASSERT_EQ(r.error, "");
    EXPECT_EQ(r.answers.checked, 12u);
    if (scale == 1.0) {
      EXPECT_TRUE(r.answers.passed()) << r.answers.first_failure;
      EXPECT_LE(r.answers.max_residual, params.tolerance);
      std::string out;
      EXPECT_EQ(runCommand({bag, "tolerance=1e-10", "--tolerance-compare", "0"}, &out), 0)
          << out;  // no params file: no answer check
    } else {
      EXPECT_FALSE(r.answers.passed());
      EXPECT_EQ(r.answers.residual_differs, 12u);
      EXPECT_NE(r.answers.first_failure.find("stamp 100.000000000: residual"), std::string::npos)
          << r.answers.first_failure;
      // The command checks the answers with the recording's parameter file beside the bag.
      ASSERT_EQ(writeParamsFile(paramsFileBeside(bag), params), "");
      std::string out;
      EXPECT_EQ(runCommand({bag, "--tolerance-compare", "1e-3", "--no-progress"}, &out), 1) << out;
      EXPECT_NE(out.find("FAIL: 12 of 12 recorded answers fail their check"), std::string::npos) << out;
      fs::remove(paramsFileBeside(bag));
    }
  }
}

// ---- the shipped bags -------------------------------------------------------------------

// MuJoCo's reference bags are named mujoco_*.bag; the others are our own output.
bool isMujocoReference(const fs::path& bag) { return bag.filename().string().rfind("mujoco_", 0) == 0; }

std::vector<fs::path> shippedBags(bool mujoco) {
  std::vector<fs::path> bags;
  for (const auto& entry : fs::directory_iterator(LCS_TEST_DATA_DIR))
    if (entry.path().extension() == ".bag" && isMujocoReference(entry.path()) == mujoco)
      bags.push_back(entry.path());
  std::sort(bags.begin(), bags.end());
  return bags;
}

lcs::core::SolverParams recordedParams(const fs::path& bag) {
  lcs::core::SolverParams params = defaultSolverParams();
  const std::string params_file = paramsFileBeside(bag.string());
  EXPECT_TRUE(fs::exists(params_file)) << params_file;
  EXPECT_EQ(loadParamsFile(params_file, &params), "");
  return params;
}

constexpr const char* kMujocoReferenceTopic = "/mujoco_bridge/reference_forces";
// Our forces against MuJoCo's efc_force on the pyramidal cone. W = efc_AR is positive
// definite (MuJoCo's R > 0), so the LCP has one solution and both solvers converge to it:
// ours to residual 1e-12 (the bags' params files), MuJoCo's PGS run to its fixed point
// (3000 sweeps, tolerance 0). The force error is about cond · residual: PGS at 1e-12 lands
// 1e-10 from MuJoCo (measured 9e-11; 1e-4 at residual 1e-6), auto/lemke/newton 2e-14.
// 1e-8 leaves 100x for another machine's rounding; a solve stopped at residual 1e-6, a row
// mapping or sign error are far above it.
constexpr double kMujocoTolerance = 1e-8;

// The correctness check: the bags of MuJoCo's own models (scripts/record-mujoco-bags)
// replayed through the node's CycleSolver with their parameters match MuJoCo's forces.
TEST(ShippedBags, MujocoReferenceReplayMatchesMujocosForces) {
  const std::vector<fs::path> bags = shippedBags(true);
  ASSERT_GE(bags.size(), 2u) << "no MuJoCo reference bags in " << LCS_TEST_DATA_DIR
                             << " (scripts/record-mujoco-bags)";
  std::size_t most_contacts = 0;
  for (const fs::path& bag : bags) {
    SCOPED_TRACE(bag.string());
    EXPECT_LT(fs::file_size(bag), 2u << 20);
    ReplayOptions options;
    options.reference_topic = kMujocoReferenceTopic;
    const ReplayResult r = replayFile(bag.string(), recordedParams(bag), options);
    ASSERT_EQ(r.error, "");
    EXPECT_EQ(r.forces_topic, "");  // no output of ours in these bags: nothing of ours to reproduce
    const Comparison& c = r.reference;
    EXPECT_GE(r.cycles, 20u);
    EXPECT_EQ(r.converged, r.cycles);
    EXPECT_EQ(c.compared, r.cycles);
    EXPECT_EQ(c.mismatched + c.missing_reference + c.missing_replay, 0u) << c.first_mismatch;
    EXPECT_LE(c.max_relative, kMujocoTolerance) << "worst cycle #" << c.worst_cycle;
    EXPECT_GT(c.max_abs, 0.0);  // two solvers, not one answer copied
    for (const CycleDifference& d : r.reference_cycles) most_contacts = std::max(most_contacts, d.contacts);
    std::printf("%s: %zu cycles, max relative difference to MuJoCo %.2e\n", bag.filename().c_str(), r.cycles,
                c.max_relative);
  }
  EXPECT_GE(most_contacts, 50u);  // rope: 29 MuJoCo contacts = 116 pyramid edges at most
}

// ... and can fail: the same bags solved loosely (residual 1e-6) are 1e-5..1e-4 from MuJoCo.
TEST(ShippedBags, MujocoReferenceCatchesAnInexactSolve) {
  for (const fs::path& bag : shippedBags(true)) {
    SCOPED_TRACE(bag.string());
    lcs::core::SolverParams loose = recordedParams(bag);
    loose.solver = lcs::core::SolverKind::kPgs;
    loose.tolerance = 1e-6;
    ReplayOptions options;
    options.reference_topic = kMujocoReferenceTopic;
    const ReplayResult r = replayFile(bag.string(), loose, options);
    ASSERT_EQ(r.error, "");
    EXPECT_TRUE(r.reference.exceeds(kMujocoTolerance)) << r.reference.max_relative;
    EXPECT_GT(r.reference.max_relative, 1e-6);
  }
}

// Change detectors: the bags of our own output (scripts/record-bags), replayed with the
// parameters recorded beside them, must reproduce the recorded forces, residuals, iteration
// counts and statuses. They say the output did not change, not that it is right (that is the
// next test); re-record them (scripts/record-bags) after a deliberate change of the forces.
TEST(ShippedBags, ChangeDetectorReplayReproducesTheRecordedForces) {
  const std::vector<fs::path> bags = shippedBags(false);
  ASSERT_GE(bags.size(), 1u) << "no recorded bags in " << LCS_TEST_DATA_DIR << " (scripts/record-bags)";
  std::uintmax_t total = 0;
  for (const fs::path& bag : shippedBags(true)) total += fs::file_size(bag);
  for (const fs::path& bag : bags) {
    SCOPED_TRACE(bag.string());
    const std::uintmax_t size = fs::file_size(bag);
    total += size;
    EXPECT_LT(size, 5u << 20);
    const ReplayResult r = replayFile(bag.string(), recordedParams(bag));
    ASSERT_EQ(r.error, "");
    const Comparison& c = r.comparison;
    EXPECT_GT(r.cycles, 20u);
    EXPECT_EQ(r.rejected, 0u);
    EXPECT_EQ(r.unpaired, 0u);
    EXPECT_EQ(c.compared, r.with_forces);
    EXPECT_EQ(c.mismatched, 0u) << c.first_mismatch;
    EXPECT_EQ(c.missing_reference, 0u) << c.first_mismatch;
    EXPECT_EQ(c.missing_replay, 0u) << c.first_mismatch;
    EXPECT_LE(c.max_relative, 1e-9) << "worst cycle #" << c.worst_cycle;
    EXPECT_EQ(c.stats_compared, r.cycles);
    EXPECT_EQ(c.iteration_differences, 0u);
    EXPECT_EQ(c.status_differences, 0u);
    EXPECT_LE(c.max_residual_relative, 1e-9);
    EXPECT_EQ(r.converged, r.solved);  // the shipped parameters converge on the shipped scenes
  }
  EXPECT_LT(total, 5u << 20) << "the shipped bags together should stay small";
}

// Beside each change detector, the independent check of every answer recorded in it, on its
// own problem with no second solve: the residual recomputed from the recorded forces and the
// recorded W and d_free is the residual the node reported and at most the recorded tolerance;
// the states are the ones the forces give; normals push; friction stays inside the cone.
TEST(ShippedBags, EveryRecordedAnswerSolvesItsOwnProblem) {
  for (const fs::path& bag : shippedBags(false)) {
    SCOPED_TRACE(bag.string());
    const lcs::core::SolverParams params = recordedParams(bag);
    ReplayOptions options;
    options.recorded_params = params;
    const ReplayResult r = replayFile(bag.string(), params, options);
    ASSERT_EQ(r.error, "");
    const AnswerChecks& a = r.answers;
    EXPECT_EQ(a.checked, r.with_forces);
    EXPECT_EQ(a.without_stats, 0u);
    EXPECT_TRUE(a.passed()) << a.first_failure;
    EXPECT_LE(a.max_residual, params.tolerance);
    std::printf(
        "%s: %zu recorded answers, recomputed residual <= %.2e (tolerance %.0e), %.1e from the recorded\n",
        bag.filename().c_str(), a.checked, a.max_residual, params.tolerance, a.max_residual_difference);
  }
}
