// The offline replay (no master): pairing, comparison, outputs and faults on bags written
// here through the node's own solve path (CycleSolver); the bags shipped in test/data:
//   - references from outside (mujoco_*.bag, scripts/record-mujoco-bags): MuJoCo's own
//     efc_force recorded beside the problems; our replay must match it (the correctness check);
//   - change detectors (the others, scripts/record-bags): our own earlier output, which the
//     replay must reproduce (equal by construction while the code is unchanged, so they only
//     detect change), each beside an independent check of every recorded answer on its own
//     problem (answer_check.h: residual, states, signs, friction cone).
#include "replay_test_util.h"

using namespace replay_test;

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
