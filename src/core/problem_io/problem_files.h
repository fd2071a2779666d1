// What every problem-file reader shares: the limits that keep a hostile file from making us
// allocate terabytes, one-line faults (ProblemFileError), and the checks made before parsing.
// Private to the io library.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/problem_io.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace lcp_contact_solver::core::problem_files {

// Larger problems are refused before anything is allocated for them: a corrupt or hostile
// header must not make us try to allocate terabytes.
constexpr long long kMaxRows = 1000000;
// Sparse-block LCPs are converted to a dense M; larger ones are refused (8 n² bytes).
constexpr long long kMaxDenseLcpRows = 8192;
// Larger files are refused before reading them into memory.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 31;
constexpr char kHdf5Signature[] = "\x89HDF\r\n\x1a\n";
constexpr std::size_t kHdf5SignatureSize = 8;

// Throws ProblemFileError "path: fault".
[[noreturn]] void fail(const std::string& path, const std::string& fault);

std::string baseName(const std::string& path);

// A token as it may appear in a one-line message: printable, short.
std::string printable(std::string_view token);

// Checks the file can be read and is not absurdly large; throws otherwise.
void checkReadableFile(const std::string& path);

std::string readWholeFile(const std::string& path);

// HDF5 puts its signature at offset 0, or after a user block at 512, 1024, 2048, ...
bool hasHdf5Signature(const std::string& path);

// Throws unless the problem read is a valid one (validateProblem, at most kMaxRows rows).
void requireValid(const std::string& path, const Problem& problem);

// Gathers entries into one 3x3 block per pair of contacts, whatever blocking the source
// used, so W ends up with one block row per contact.
class ContactBlockBuilder {
 public:
  explicit ContactBlockBuilder(int contacts) : rows_(contacts) {}

  void add(int row, int col, double value) {
    auto& block = rows_[row / 3].try_emplace(col / 3, Eigen::Matrix3d::Zero()).first->second;
    block(row % 3, col % 3) += value;
  }

  BlockSparseMatrix build() const {
    BlockSparseMatrix W = BlockSparseMatrix::withBlockSizes(std::vector<int>(rows_.size(), 3));
    for (const auto& row : rows_) {
      W.beginRow();
      for (const auto& [col, block] : row) W.addBlock(col, block);
    }
    return W;
  }

 private:
  std::vector<std::map<int, Eigen::Matrix3d>> rows_;
};

}  // namespace lcp_contact_solver::core::problem_files
