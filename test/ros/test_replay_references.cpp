// The replay against references: from outside (MuJoCo), recorded answers checked, shipped bags.
#include "replay_test_util.h"

using namespace replay_test;

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
