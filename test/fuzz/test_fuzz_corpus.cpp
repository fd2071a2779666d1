// Replays every input kept under test/fuzz/corpus/<target>/ (the seeds, every input a fuzzing
// run found to crash, added after the fix, and the corpus the runs grew, minimized with
// libFuzzer's -merge=1) through the fuzz targets' functions in the normal build, so `make test`
// (and its sanitizer pass) keeps them fixed.
#include "fuzz_targets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> corpus(const std::string& target) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(fs::path(LCS_FUZZ_CORPUS_DIR) / target))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string bytesOf(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

template <typename Target>
void replay(const std::string& target, Target run) {
  const std::vector<fs::path> files = corpus(target);
  ASSERT_FALSE(files.empty()) << "no corpus for " << target;
  for (const fs::path& file : files) {
    const std::string bytes = bytesOf(file);
    EXPECT_EQ(run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "") << file.filename();
  }
  std::printf("  %s: %zu inputs replayed\n", target.c_str(), files.size());
}

}  // namespace

TEST(FuzzCorpus, DatReader) { replay("dat_reader", lcs_fuzz::datReaderOneInput); }

TEST(FuzzCorpus, MsgSolve) { replay("msg_solve", lcs_fuzz::msgSolveOneInput); }

// The shipped malformed problem files are good reader inputs too.
TEST(FuzzCorpus, MalformedProblemFiles) {
  for (const auto& entry : fs::directory_iterator(fs::path(LCS_TEST_DATA_DIR) / "malformed")) {
    const std::string bytes = bytesOf(entry.path());
    EXPECT_EQ(lcs_fuzz::datReaderOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()),
              "")
        << entry.path().filename();
  }
}
