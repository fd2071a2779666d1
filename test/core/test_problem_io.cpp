// Tests of the problem file readers (problem_io.h) on the shared reference problems and on
// malformed files written at run time.
#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

namespace fs = std::filesystem;

const fs::path kProblemsDir = LCS_PROBLEMS_DIR;
const fs::path kTestDataDir = LCS_TEST_DATA_DIR;

std::vector<fs::path> sharedProblemFiles() {
  std::vector<fs::path> files;
  for (const char* folder : {"lcp", "fc3d"})
    for (const auto& entry : fs::directory_iterator(kProblemsDir / folder))
      if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string fileText(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

// What the first numbers of a Siconos .dat file announce, read independently of the reader.
struct DatHeader {
  bool fc3d = false;
  int contacts = 0;
  int rows = 0;
  int storage = 0;
};

DatHeader readDatHeader(const fs::path& path) {
  std::istringstream in(fileText(path));
  long long a = 0, b = 0, c = 0, d = 0;
  in >> a >> b >> c >> d;
  DatHeader header;
  if (a == 3 && (c == 0 || c == 1)) {  // 3, nc, storage, rows
    header = {true, static_cast<int>(b), static_cast<int>(d), static_cast<int>(c)};
  } else {  // n, storage, rows, cols
    header = {false, static_cast<int>(a), static_cast<int>(a), static_cast<int>(b)};
  }
  return header;
}

std::vector<double> muOf(const Problem& problem) {
  std::vector<double> mu;
  for (const Contact& c : problem.contacts) mu.push_back(c.mu);
  return mu;
}

// A fresh folder per test for the malformed files.
class ProblemIoFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) / (std::string("lcs_problem_io_") + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& content) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << content;
    return path.string();
  }

  // Expects reading `path` to throw a one-line ProblemFileError naming the file and
  // containing `fault`; returns the message.
  static std::string expectFault(const std::string& path, const std::string& fault) {
    try {
      readProblemFile(path);
    } catch (const ProblemFileError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(fault), std::string::npos) << "expected '" << fault << "' in: " << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      return message;
    } catch (const std::exception& e) {
      ADD_FAILURE() << path << ": wrong exception type: " << e.what();
      return "";
    }
    ADD_FAILURE() << path << ": read without error, '" << fault << "' expected";
    return "";
  }

  fs::path dir_;
};

// ---- the shared reference problems --------------------------------------------------------

TEST(SharedProblems, AllFortySixRead) {
  const auto files = sharedProblemFiles();
  EXPECT_EQ(files.size(), 46u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    Problem problem;
    ASSERT_NO_THROW(problem = readProblemFile(file.string()));
    EXPECT_EQ(problem.name, file.filename().string());
    EXPECT_EQ(validateProblem(problem), "");
  }
}

TEST(SharedProblems, DatCountsAndStorageMatchTheirHeaders) {
  for (const fs::path& file : sharedProblemFiles()) {
    if (file.extension() != ".dat") continue;
    SCOPED_TRACE(file.string());
    const DatHeader header = readDatHeader(file);
    const Problem problem = readSiconosDat(file.string());
    ASSERT_EQ(static_cast<int>(problem.contacts.size()), header.contacts);
    EXPECT_EQ(problem.rowCount(), header.rows);
    EXPECT_EQ(problem.d_free.size(), header.rows);
    EXPECT_EQ(complianceRows(problem.W), header.rows);
    const ContactType expected_type = header.fc3d ? ContactType::kFrictional : ContactType::kFrictionless;
    for (const Contact& c : problem.contacts) {
      EXPECT_EQ(c.type, expected_type);
      EXPECT_GE(c.mu, 0.0);
    }
    // FC3D sparse files stay block-sparse; everything else is dense (LCPs are small).
    const bool block_sparse = std::holds_alternative<BlockSparseMatrix>(problem.W);
    EXPECT_EQ(block_sparse, header.fc3d && header.storage == 1);
  }
}

TEST(SharedProblems, KnownSizes) {
  struct Expected {
    const char* file;
    int contacts;
  };
  for (const Expected& e :
       {Expected{"fc3d/Rover1039.dat", 4}, Expected{"fc3d/Rover1040.dat", 5},
        Expected{"fc3d/Rover11035.dat", 1}, Expected{"fc3d/Rover4396.dat", 2},
        Expected{"fc3d/NESpheres_10_1.dat", 9}, Expected{"fc3d/BoxesStack1-i100000-32.hdf5.dat", 52},
        Expected{"fc3d/OneObject-i1028-138.hdf5.dat", 23}, Expected{"fc3d/Capsules-i100-1090.dat", 276},
        Expected{"fc3d/LMGC_100_PR_PerioBox-i00361-60-03000.hdf5", 60}}) {
    SCOPED_TRACE(e.file);
    const Problem problem = readProblemFile((kProblemsDir / e.file).string());
    EXPECT_EQ(static_cast<int>(problem.contacts.size()), e.contacts);
    EXPECT_EQ(problem.rowCount(), 3 * e.contacts);
  }
  const Problem lcp = readProblemFile((kProblemsDir / "lcp/lcp_tobenna.dat").string());
  EXPECT_EQ(lcp.contacts.size(), 40u);
}

TEST(SharedProblems, Rover1039ValuesAreColumnMajor) {
  const Problem problem = readSiconosDat((kProblemsDir / "fc3d/Rover1039.dat").string());
  const auto& W = std::get<Eigen::MatrixXd>(problem.W);
  // The file's first printed line is W's first column.
  EXPECT_DOUBLE_EQ(W(0, 0), 1.399132380123367484781038e-02);
  EXPECT_DOUBLE_EQ(W(1, 0), 1.205376840899833462694701e-03);
  EXPECT_DOUBLE_EQ(W(2, 0), -2.379213748917135586025129e-03);
  EXPECT_DOUBLE_EQ(problem.d_free[0], -9.255873583433080198368259e-02);
  EXPECT_DOUBLE_EQ(problem.d_free[1], -1.644109012478871534312930e-01);
  for (const Contact& c : problem.contacts) EXPECT_DOUBLE_EQ(c.mu, 0.7);
}

TEST(SharedProblems, LcpWithTrailingRemarkReads) {
  // lcp_CPS_1.dat ends with a text remark after q.
  const Problem problem = readSiconosDat((kProblemsDir / "lcp/lcp_CPS_1.dat").string());
  ASSERT_EQ(problem.contacts.size(), 2u);
  EXPECT_EQ(toDense(problem.W), Eigen::MatrixXd::Ones(2, 2));
  EXPECT_EQ(problem.d_free, Eigen::VectorXd::Constant(2, -1.0));
}

// Dense and sparse-block files of the same problem must give the same numbers.
void expectSameProblem(const char* dense_file, const char* sparse_file) {
  SCOPED_TRACE(std::string(dense_file) + " vs " + sparse_file);
  const Problem dense = readSiconosDat((kProblemsDir / dense_file).string());
  const Problem sparse = readSiconosDat((kProblemsDir / sparse_file).string());
  ASSERT_EQ(dense.rowCount(), sparse.rowCount());
  EXPECT_EQ(toDense(dense.W), toDense(sparse.W));
  EXPECT_EQ(dense.d_free, sparse.d_free);
  EXPECT_EQ(muOf(dense), muOf(sparse));
}

TEST(SharedProblems, DenseAndSparseBlockFilesAgree) {
  expectSameProblem("fc3d/FC3D_Example1.dat", "fc3d/FC3D_Example1_SBM.dat");
  expectSameProblem("lcp/lcp_ortiz.dat", "lcp/lcp_ortiz_block.dat");
  expectSameProblem("lcp/lcp_deudeu.dat", "lcp/lcp_deudeu_block.dat");
  expectSameProblem("lcp/lcp_trivial.dat", "lcp/lcp_trivial_block.dat");
}

TEST(SharedProblems, SparseFc3dHasOneBlockRowPerContact) {
  const Problem problem = readSiconosDat((kProblemsDir / "fc3d/BoxesStack1-i100000-32.hdf5.dat").string());
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  EXPECT_EQ(W.validate(), "");
  ASSERT_EQ(W.blockCount(), 52);
  for (int i = 0; i <= W.blockCount(); ++i) EXPECT_EQ(W.block_offset[i], 3 * i);
  EXPECT_EQ(W.block_col.size(), 592u);  // the file's stored block count
  // Stored block by block, as the file gives them: the diagonal blocks are there.
  for (int i = 0; i < W.blockCount(); ++i) {
    bool has_diagonal = false;
    for (int k = W.row_start[i]; k < W.row_start[i + 1]; ++k) has_diagonal |= W.block_col[k] == i;
    EXPECT_TRUE(has_diagonal) << "block row " << i;
  }
}

TEST(SharedProblems, FclibProblemIsBlockSparseAndSymmetric) {
  const std::string path = (kProblemsDir / "fc3d/LMGC_100_PR_PerioBox-i00361-60-03000.hdf5").string();
  const Problem problem = readFclibHdf5(path);
  EXPECT_EQ(problem.name, "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5");
  ASSERT_EQ(problem.contacts.size(), 60u);
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  EXPECT_EQ(W.validate(), "");
  for (int i = 0; i <= W.blockCount(); ++i) EXPECT_EQ(W.block_offset[i], 3 * i);
  // W = H M⁻¹ Hᵀ: symmetric with a positive normal diagonal, whatever the file's storage.
  const Eigen::MatrixXd dense = W.toDense();
  EXPECT_LE((dense - dense.transpose()).cwiseAbs().maxCoeff(), 1e-12 * dense.cwiseAbs().maxCoeff());
  for (int c = 0; c < 60; ++c) EXPECT_GT(dense(3 * c, 3 * c), 0.0) << "contact " << c;
  for (const Contact& c : problem.contacts) {
    EXPECT_EQ(c.type, ContactType::kFrictional);
    EXPECT_GE(c.mu, 0.0);
  }
  EXPECT_GT(problem.d_free.norm(), 0.0);
  // Dispatch by content gives the same problem.
  const Problem dispatched = readProblemFile(path);
  EXPECT_EQ(toDense(dispatched.W), dense);
  EXPECT_EQ(dispatched.d_free, problem.d_free);
}

// ---- malformed files ----------------------------------------------------------------------

TEST_F(ProblemIoFiles, ShippedTextFileIsRefused) {
  const std::string path = (kTestDataDir / "not_a_problem.dat").string();
  expectFault(path, "'This'");
}

TEST_F(ProblemIoFiles, MissingFileAndDirectory) {
  expectFault((dir_ / "no_such_file.dat").string(), "no such file");
  expectFault(dir_.string(), "directory");
}

TEST_F(ProblemIoFiles, EmptyAndTruncatedFiles) {
  expectFault(write("empty.dat", ""), "truncated");
  expectFault(write("spaces.dat", "  \n\t\n"), "truncated");
  const std::string rover = fileText(kProblemsDir / "fc3d/Rover1039.dat");
  expectFault(write("half_rover.dat", rover.substr(0, rover.size() / 2)), "truncated");
  // Cut inside mu: every number present but the last contact's friction.
  const std::string lcp = "2 0 2 2 2 2 1 0 0 1 -1";
  expectFault(write("lcp_no_q1.dat", lcp), "truncated");
  expectFault(write("fc3d_no_mu.dat", "3 1 0 3 3 3 3 1 0 0 0 1 0 0 0 1 -1 0 0"), "truncated");
}

TEST_F(ProblemIoFiles, NonNumericTokens) {
  expectFault(write("word_in_matrix.dat", "2 0 2 2 2 2 1 0 zero 1 -1 -1"), "found 'zero'");
  expectFault(write("float_size.dat", "2.5 0 2 2 2 2 1 0 0 1 -1 -1"), "integer");
  expectFault(write("binary.dat", std::string("2 0 2 2 2 2 1\x01\x02 0 0 1 -1 -1", 28)), "found '1\?\?'");
}

TEST_F(ProblemIoFiles, NonFiniteNumbers) {
  expectFault(write("nan.dat", "2 0 2 2 2 2 1 0 nan 1 -1 -1"), "not finite");
  expectFault(write("inf.dat", "2 0 2 2 2 2 1 0 0 1 -inf -1"), "not finite");
  expectFault(write("overflow.dat", "2 0 2 2 2 2 1 0 0 1e999 -1 -1"), "not finite");
}

TEST_F(ProblemIoFiles, BadSizes) {
  expectFault(write("negative.dat", "-2 0 2 2 2 2 1 0 0 1 -1 -1"), "negative");
  expectFault(write("huge.dat", "2000000 0 2000000 2000000 2000000 2000000 1"), "too large");
  expectFault(write("huge_nc.dat", "3 900000 0 2700000 2700000 1"), "too large");
  // Header promises a 1e6 x 1e6 dense matrix: refused without allocating it.
  expectFault(write("huge_dense.dat", "1000000 0 1000000 1000000 1000000 1000000 1 2 3"), "truncated");
  expectFault(write("lcp_not_square.dat", "2 0 2 3 2 3 1 0 0 1 0 0 -1 -1"), "2x3");
  expectFault(write("lcp_wrong_n.dat", "3 0 2 2 2 2 1 0 0 1 -1 -1 -1"), "3x3 expected");
  expectFault(write("dense_dims.dat", "2 0 2 2 2 1 1 0 0 1 -1 -1"), "header says 2x2");
  expectFault(write("storage.dat", "2 7 2 2 2 2 1 0 0 1 -1 -1"), "unknown matrix storage 7");
  // FC3D: nc = 2 but a 3x3 matrix.
  expectFault(write("fc3d_rows.dat", "3 2 0 3 3 3 3 1 0 0 0 1 0 0 0 1 -1 0 0 0.5"), "6x6 expected");
  expectFault(write("fc3d_dim.dat", "2 1 0 3 3 3 3 1 0 0 0 1 0 0 0 1 -1 0 0 0.5"), "2x2 expected");
  // Siconos' 2-D friction files (one contact: 2x2 W, 2 q, 1 mu) are named as such.
  expectFault(write("fc2d.dat", "2 1 0 2 2 2 2 1 0 0 1 -1 0 0.5"), "2-D frictional contact problem");
  expectFault(write("no_contacts.dat", "3 0 0 0 0 0 0"), "no contacts");
  // A tiny sparse file cannot make us allocate a huge dense LCP matrix.
  expectFault(write("huge_sparse_lcp.dat", "900000 1 900000 900000 1 1 1 900000 900000"),
              "too large to convert to dense");
}

TEST_F(ProblemIoFiles, NegativeMu) {
  expectFault(write("negative_mu.dat", "3 1 0 3 3 3 3 1 0 0 0 1 0 0 0 1 -1 0 0 -0.5"), "mu[0] is negative");
}

// A valid sparse-block FC3D file with one contact, to corrupt one field at a time.
std::string sparseOneContact(const std::string& block_index = "0", const std::string& row_ptr = "0 1",
                             const std::string& col_idx = "0") {
  return "3 1 1 3 3 1 1 1 3 3 2 1 " + row_ptr + " " + col_idx + " " + block_index +
         " 1 0 0 0 1 0 0 0 1  -1 0 0  0.5";
}

TEST_F(ProblemIoFiles, SparseBlockStructureErrors) {
  ASSERT_NO_THROW(readProblemFile(write("good.dat", sparseOneContact())));
  expectFault(write("label.dat", sparseOneContact("4")), "labelled 4");
  expectFault(write("row_ptr.dat", sparseOneContact("0", "1 1")), "block row pointers");
  expectFault(write("col_idx.dat", sparseOneContact("0", "0 1", "1")), "out of range");
  expectFault(write("filled1.dat", "3 1 1 3 3 1 1 1 3 3 5 1 0 1 0 0 1 0 0 0 1 0 0 0 1 -1 0 0 0.5"),
              "filled1");
  expectFault(write("ends.dat", "3 1 1 3 3 1 1 1 2 3 2 1 0 1 0 0 1 0 0 0 1 0 0 0 1 -1 0 0 0.5"), "end at 2");
  expectFault(write("twice.dat",
                    "3 1 1 3 3 2 1 1 3 3 2 2 0 2 0 0 0 1 0 0 0 1 0 0 0 1 1 1 0 0 0 1 0 0 0 1 -1 0 0 0.5"),
              "same block column twice");
}

TEST_F(ProblemIoFiles, SparseBlocksSpanningContactsAreSplit) {
  // Two contacts stored as a single 6x6 block: W must still get one block row per contact.
  std::ostringstream file;
  file << "3 2 1 6 6 1 1 1 6 6 2 1 0 1 0 0";
  Eigen::MatrixXd M(6, 6);
  for (int c = 0; c < 6; ++c)
    for (int r = 0; r < 6; ++r) M(r, c) = 10 * r + c + (r == c ? 100 : 0);
  for (int c = 0; c < 6; ++c)
    for (int r = 0; r < 6; ++r) file << " " << M(r, c);
  file << "  -1 0 0 -2 0 0  0.5 0.25";
  const Problem problem = readProblemFile(write("six.dat", file.str()));
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  EXPECT_EQ(W.block_offset, (std::vector<int>{0, 3, 6}));
  EXPECT_EQ(W.toDense(), M);
  EXPECT_EQ(muOf(problem), (std::vector<double>{0.5, 0.25}));
}

TEST_F(ProblemIoFiles, TrailingTextIsAllowed) {
  const std::string rover = fileText(kProblemsDir / "fc3d/Rover4396.dat");
  const Problem problem = readProblemFile(write("rover_notes.dat", rover + "\nsolved by: someone 1 2 3\n"));
  EXPECT_EQ(problem.contacts.size(), 2u);
  EXPECT_EQ(problem.name, "rover_notes.dat");
}

TEST_F(ProblemIoFiles, Hdf5SignatureDispatch) {
  // A .hdf5 name with text content is read as text; text content is not HDF5.
  const std::string text_named_hdf5 = write("lcp.hdf5", "1 0 1 1 1 1 2 -1");
  EXPECT_EQ(readProblemFile(text_named_hdf5).contacts.size(), 1u);
  try {
    readFclibHdf5(text_named_hdf5);
    ADD_FAILURE() << "text read as HDF5";
  } catch (const ProblemFileError& e) {
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos) << e.what();
  }
  // The signature followed by garbage: HDF5 fails, we report it in one line.
  expectFault(write("garbage.hdf5", std::string("\x89HDF\r\n\x1a\n", 8) + std::string(600, 'x')),
              "HDF5 cannot open");
  // A truncated real FCLIB file.
  const std::string lmgc = fileText(kProblemsDir / "fc3d/LMGC_100_PR_PerioBox-i00361-60-03000.hdf5");
  expectFault(write("truncated.hdf5", lmgc.substr(0, lmgc.size() / 2)), "HDF5 cannot open");
}

// Small FCLIB files written by test/data/make_fclib_test_files.cpp (valid ones through
// fclib_write_local). Their W is non-symmetric, W(r, c) = 10 (r + 1) + (c + 1), so a
// transposed read would show.
double fclibTestEntry(int r, int c) { return 10.0 * (r + 1) + (c + 1); }

TEST(FclibFiles, CompressedColumnStorage) {
  const Problem problem = readProblemFile((kTestDataDir / "fclib_csc_2c.hdf5").string());
  ASSERT_EQ(problem.contacts.size(), 2u);
  EXPECT_EQ(muOf(problem), (std::vector<double>{0.3, 0.5}));
  EXPECT_EQ(problem.d_free, (Eigen::VectorXd(6) << -1, 0.1, 0.2, -2, 0.3, 0.4).finished());
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  // Contact-pair blocks (0,0), (0,1), (1,1) are stored; (1,0) is empty.
  EXPECT_EQ(W.row_start, (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(W.block_col, (std::vector<int>{0, 1, 1}));
  const Eigen::MatrixXd dense = W.toDense();
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      EXPECT_EQ(dense(r, c), (r >= 3 && c < 3) ? 0.0 : fclibTestEntry(r, c)) << r << "," << c;
}

TEST(FclibFiles, TripletStorage) {
  const Problem problem = readProblemFile((kTestDataDir / "fclib_triplet_1c.hdf5").string());
  ASSERT_EQ(problem.contacts.size(), 1u);
  EXPECT_EQ(problem.contacts[0].mu, 0.4);
  const Eigen::MatrixXd dense = toDense(problem.W);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(dense(r, c), fclibTestEntry(r, c)) << r << "," << c;
}

TEST_F(ProblemIoFiles, FaultyFclibFilesAreRefusedWithoutEndingTheProcess) {
  // fclib_read_local itself would exit(1) or overflow on several of these.
  const std::pair<const char*, const char*> cases[] = {
      {"fclib_missing_mu.hdf5", "lacks /fclib_local/vectors/mu"},
      {"fclib_short_p.hdf5", "/fclib_local/W/p has 6 entries, 7 expected"},
      {"fclib_global_only.hdf5", "only local problems"},
      {"fclib_spacedim2.hdf5", "dimension 2"},
      {"fclib_mixed.hdf5", "mixed problems"},
      {"fclib_bad_index.hdf5", "out of range"},
      {"fclib_nan_q.hdf5", "non-finite"},
  };
  for (const auto& [file, fault] : cases) expectFault((kTestDataDir / file).string(), fault);
}

}  // namespace
}  // namespace lcp_contact_solver::core
