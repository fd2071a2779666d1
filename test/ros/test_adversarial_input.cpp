// Adversarial input without a master: the message conversion's row limits (the 10⁶-row
// hard limit of max_rows = 0, and the contact-count check that refuses an oversized array
// before allocating per contact), and malformed bags for the replay tool (bad messages in
// a good bag, a message whose array length runs past its end, one whose length claims
// terabytes, a topic of the wrong type, bytes flipped in a compressed chunk): a clear
// one-line error or rejected cycles, exit status 2 for an unreadable bag, never a crash.
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/bag_replay.h"
#include "replay/replay_command.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <std_msgs/String.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;
namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver::ContactPoint;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

// AddressSanitizer's operator new cannot throw std::bad_alloc: an allocation it cannot
// serve ends the process ("allocator is out of memory") whatever ASAN_OPTIONS say.
#if defined(__SANITIZE_ADDRESS__)
#define LCS_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LCS_UNDER_ASAN 1
#endif
#endif
#ifndef LCS_UNDER_ASAN
#define LCS_UNDER_ASAN 0
#endif

namespace {

fs::path tmpDir() {
  static const fs::path dir = [] {
    fs::path d = fs::path(LCS_TEST_TMP_DIR) / ("test_adversarial_input_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string tmpFile(const std::string& name) { return (tmpDir() / name).string(); }

class RemoveTmpDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(tmpDir(), ignored);
  }
};
const ::testing::Environment* const kRemoveTmpDir = ::testing::AddGlobalTestEnvironment(new RemoveTmpDir);

// ---- conversion limits ----------------------------------------------------------------------

// max_rows = 0 means no limit of the user's, but the conversion still refuses more than 10⁶
// rows before sizing W or d_free. 166 667 six-row bilateral contacts (1 000 002 rows, ~50 MB
// of message objects in this test; a 10⁶-contact array of the same kind would be ~300 MB).
TEST(ConversionLimits, HardRowLimitWithoutMaxRows) {
  Scene s = makeScene(1, ros::Time(1.0));
  ContactPoint c = s.contacts.contacts[3];
  c.type = ContactPoint::BILATERAL;
  c.rows = 6;
  c.d_free.assign(6, -0.01);
  s.contacts.contacts.assign(166667, c);
  for (std::size_t i = 0; i < s.contacts.contacts.size(); ++i)
    s.contacts.contacts[i].id = static_cast<std::int64_t>(i);
  s.compliance.rows = 1000002;
  s.compliance.data.clear();
  lcs::core::Problem problem;
  std::vector<ContactFrame> frames;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string error = toProblem(s.contacts, s.compliance, 0, &problem, &frames);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(error.find("1000002 rows, more than the limit of 1000000"), std::string::npos) << error;
  EXPECT_EQ(problem.d_free.size(), 0);  // nothing sized from the claimed rows
  EXPECT_EQ(complianceRows(problem.W), 0);
  EXPECT_LT(seconds, 5.0);
}

// An array with more contacts than the row limit is refused on its size alone: no per-
// contact work (the 100 000-contact array of the rostest, here against max_rows = 1000).
TEST(ConversionLimits, ContactCountOverTheLimitIsRefusedFirst) {
  Scene s = makeScene(1, ros::Time(1.0));
  ContactPoint c;  // default: even invalid contents are not looked at
  s.contacts.contacts.assign(100000, c);
  lcs::core::Problem problem;
  std::vector<ContactFrame> frames;
  const std::string error = toProblem(s.contacts, s.compliance, 1000, &problem, &frames);
  EXPECT_EQ(error, "the array has 100000 contacts, more than the row limit of 1000");
  EXPECT_TRUE(problem.contacts.empty());
  EXPECT_TRUE(frames.empty());
}

// ---- malformed bags for the replay tool ------------------------------------------------------

int runReplay(const std::vector<std::string>& args, std::string* out, std::string* err) {
  std::ostringstream o, e;
  const int code = runReplayCommand(args, o, e);
  *out = o.str();
  *err = e.str();
  return code;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

void expectUnreadable(const std::string& path, const std::string& what) {
  ReplayOptions options;
  options.bag = path;
  const ReplayResult r = replayBag(options, defaultSolverParams());
  EXPECT_NE(r.error, "") << what;
  EXPECT_EQ(r.error.find('\n'), std::string::npos) << what << ": " << r.error;
  std::string out, err;
  EXPECT_EQ(runReplay({path, "--quiet"}, &out, &err), 2) << what << ": " << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << what << ": " << err;
  EXPECT_EQ(err.rfind("replay: ", 0), 0u) << what << ": " << err;
  std::printf("  %s: %s", what.c_str(), err.c_str());
}

// A well-formed bag whose messages are adversarial: the replay solves the good pairs,
// rejects the bad ones (counted, not fatal), writes only finite forces, exits 0.
TEST(MalformedBags, BadMessagesInAGoodBagAreRejectedCycles) {
  const std::string path = tmpFile("bad_messages.bag");
  const std::string out_bag = tmpFile("bad_messages.out.bag");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::function<void(Scene*)>> faults = {
      [nan](Scene* s) { s->contacts.contacts[0].d_free[0] = nan; },
      [](Scene* s) { s->compliance.data[3] = std::numeric_limits<double>::infinity(); },
      [](Scene* s) { s->contacts.contacts.clear(); },
      [](Scene* s) { s->compliance.rows = 3; },
      [](Scene* s) { s->contacts.contacts[1].mu = -3.0; },
      [](Scene* s) { s->contacts.contacts[2].id = s->contacts.contacts[1].id; },
      [](Scene* s) { s->contacts.contacts[0].normal = lcp_contact_solver_test::vec(0, 0, 0); },
  };
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (std::size_t k = 0; k < 2 * faults.size(); ++k) {
      Scene s = makeScene(100, ros::Time(10.0 + 0.01 * k));
      if (k % 2 == 1) faults[k / 2](&s);
      bag.write("/contacts", ros::Time(1000.0 + 0.01 * k), s.contacts);
      bag.write("/compliance", ros::Time(1000.0 + 0.01 * k), s.compliance);
    }
  }
  ReplayOptions options;
  options.bag = path;
  options.out_bag = out_bag;
  options.keep_cycles = true;
  const ReplayResult r = replayBag(options, defaultSolverParams());
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.cycles, 2 * faults.size());
  EXPECT_EQ(r.rejected, faults.size());
  EXPECT_EQ(r.solved, faults.size());
  for (const ReplayCycle& cycle : r.cycles_kept) {
    EXPECT_TRUE(allFinite(cycle.stats));
    if (cycle.has_forces) {
      EXPECT_TRUE(allFinite(cycle.forces));
    }
    if (!cycle.stats.success) {
      EXPECT_EQ(cycle.stats.status, "invalid_input");
      EXPECT_FALSE(cycle.stats.message.empty());
    }
  }
  std::string out, err;
  EXPECT_EQ(runReplay({path, "--quiet"}, &out, &err), 0) << err;
}

// A ContactArray whose `contacts` length runs past the message (a few more than stored),
// and one whose length claims 2³² − 1 contacts (~1 TB): deserialization stops at the end of
// the buffer, or the allocation fails (std::bad_alloc, which the replay reports); either
// way a one-line error, exit status 2. The second is skipped in the sanitizer build (see
// LCS_UNDER_ASAN): the normal build runs it.
TEST(MalformedBags, CorruptArrayLengthsAreReadErrors) {
  for (std::uint32_t claimed : {6u, 0xFFFFFFFFu}) {
    if (claimed == 0xFFFFFFFFu && LCS_UNDER_ASAN) {
      std::printf("  contacts length %u: skipped under AddressSanitizer (its new cannot throw bad_alloc)\n",
                  claimed);
      continue;
    }
    const std::string good = tmpFile("good_for_length.bag");
    const std::string marker = "MARKER_FRAME_ID_0123456789";
    {
      rosbag::Bag bag(good, rosbag::bagmode::Write);  // uncompressed: the bytes are in the file as is
      Scene s = makeScene(200, ros::Time(20.0));
      s.contacts.header.frame_id = marker;
      bag.write("/contacts", ros::Time(2000.0), s.contacts);
      bag.write("/compliance", ros::Time(2000.0), s.compliance);
    }
    std::string bytes = readBytes(good);
    const std::size_t at = bytes.find(marker);
    ASSERT_NE(at, std::string::npos);
    // After the header's frame_id comes the uint32 length of `contacts` (4 in the scene).
    const std::size_t length_at = at + marker.size();
    ASSERT_EQ(static_cast<unsigned char>(bytes[length_at]), 4u);
    for (int b = 0; b < 4; ++b) bytes[length_at + b] = static_cast<char>((claimed >> (8 * b)) & 0xFF);
    const std::string corrupt = tmpFile("corrupt_length.bag");
    writeBytes(corrupt, bytes);
    expectUnreadable(corrupt, "contacts length " + std::to_string(claimed));
  }
}

// The contacts topic carries another type; bytes flipped inside a compressed chunk.
TEST(MalformedBags, WrongTypesAndCorruptChunks) {
  {
    const std::string path = tmpFile("wrong_type.bag");
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    std_msgs::String text;
    text.data = "not contacts";
    bag.write("/contacts", ros::Time(1.0), text);
    bag.write("/compliance", ros::Time(1.0), text);
    bag.close();
    expectUnreadable(path, "wrong message type");
  }
  for (auto compression : {rosbag::compression::LZ4, rosbag::compression::BZ2}) {
    const std::string good = tmpFile("compressed.bag");
    {
      rosbag::Bag bag(good, rosbag::bagmode::Write);
      bag.setCompression(compression);
      for (int k = 0; k < 20; ++k) {
        const Scene s = makeScene(300, ros::Time(30.0 + 0.01 * k));
        bag.write("/contacts", ros::Time(3000.0 + 0.01 * k), s.contacts);
        bag.write("/compliance", ros::Time(3000.0 + 0.01 * k), s.compliance);
      }
    }
    std::string bytes = readBytes(good);
    // Flip a run of bytes in the middle of the file (inside the chunk data).
    for (std::size_t i = bytes.size() / 3; i < bytes.size() / 3 + 64; ++i)
      bytes[i] = static_cast<char>(~bytes[i]);
    const std::string corrupt = tmpFile("corrupt_chunk.bag");
    writeBytes(corrupt, bytes);
    ReplayOptions options;
    options.bag = corrupt;
    const ReplayResult r = replayBag(options, defaultSolverParams());
    // Depending on what the flipped bytes hit, the chunk fails to decompress (an error) or
    // a message decodes to different values (solved or rejected): never a crash.
    EXPECT_EQ(r.error.find('\n'), std::string::npos) << r.error;
    std::string out, err;
    const int code = runReplay({corrupt, "--quiet"}, &out, &err);
    EXPECT_TRUE(code == 0 || code == 2) << code << ": " << err;
    std::printf("  corrupt %s chunk: exit %d, %s", compression == rosbag::compression::LZ4 ? "lz4" : "bz2",
                code, err.empty() ? "no error\n" : err.c_str());
  }
}

}  // namespace
