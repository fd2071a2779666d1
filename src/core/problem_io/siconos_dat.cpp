// Siconos .dat files (the numerics test data: LCPs and FC3D problems), read into a Problem.
#include "problem_files.h"

#include <array>
#include <Eigen/Core>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string_view>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

using namespace problem_files;

// Reads whitespace-separated numbers one by one, remembering the line for messages.
class TokenReader {
 public:
  TokenReader(std::string path, std::string content) : path_(std::move(path)), content_(std::move(content)) {}

  const std::string& path() const { return path_; }

  [[noreturn]] void failHere(const std::string& fault) const {
    fail(path_, "line " + std::to_string(line_) + ": " + fault);
  }

  // A non-negative integer no larger than `max`.
  long long readSize(const std::string& what, long long max) {
    const long long value = readInt(what);
    if (value < 0) failHere(what + " is negative (" + std::to_string(value) + ")");
    if (value > max)
      failHere(what + " is too large (" + std::to_string(value) + ", at most " + std::to_string(max) +
               " allowed)");
    return value;
  }

  long long readInt(const std::string& what) {
    const std::string token(next(what));
    errno = 0;
    char* end = nullptr;
    const long long value = std::strtoll(token.c_str(), &end, 10);
    if (end != token.c_str() + token.size() || token.empty())
      failHere("expected " + what + " (an integer), found '" + printable(token) + "'");
    if (errno == ERANGE) failHere(what + " is out of range ('" + printable(token) + "')");
    return value;
  }

  double readDouble(const std::string& what) {
    const std::string token(next(what));
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if (end != token.c_str() + token.size() || token.empty())
      failHere("expected " + what + " (a number), found '" + printable(token) + "'");
    if (!std::isfinite(value)) failHere(what + " is not finite ('" + printable(token) + "')");
    return value;
  }

  // Throws unless `count` more numbers can still follow: each needs at least one character
  // and one separator. Guards allocations sized from the file's own header.
  void requireAvailable(long long count, const std::string& what) const {
    const long long bytes_left = static_cast<long long>(content_.size() - pos_);
    if (count > (bytes_left + 1) / 2)
      fail(path_, "truncated: " + what + " needs " + std::to_string(count) + " numbers but only " +
                      std::to_string(bytes_left) + " bytes remain");
  }

 private:
  std::string_view next(const std::string& what) {
    skipSpace();
    if (pos_ >= content_.size()) fail(path_, "truncated: the file ends before " + what);
    const std::size_t start = pos_;
    while (pos_ < content_.size() && !isSpace(content_[pos_])) ++pos_;
    return std::string_view(content_).substr(start, pos_ - start);
  }

  void skipSpace() {
    while (pos_ < content_.size() && isSpace(content_[pos_])) {
      if (content_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }

  static bool isSpace(char ch) { return std::isspace(static_cast<unsigned char>(ch)) != 0; }

  std::string path_;
  std::string content_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

// Siconos' sparse block matrix as written: CSR over blocks of varying sizes.
struct SiconosBlockMatrix {
  int rows = 0;
  int cols = 0;
  std::vector<int> row_offset;  // size nbBlockRows + 1
  std::vector<int> col_offset;  // size nbBlockCols + 1
  std::vector<int> row_start;   // CSR block row pointers, size nbBlockRows + 1
  std::vector<int> block_col;   // block column of each stored block
  std::vector<Eigen::MatrixXd> blocks;
};

struct MatrixHeader {
  int storage = 0;
  int rows = 0;
  int cols = 0;
};

MatrixHeader readMatrixHeader(TokenReader& in) {
  MatrixHeader header;
  const long long storage = in.readInt("the matrix storage");
  if (storage != 0 && storage != 1)
    in.failHere("unknown matrix storage " + std::to_string(storage) + " (0 dense, 1 sparse block expected)");
  header.storage = static_cast<int>(storage);
  header.rows = static_cast<int>(in.readSize("the matrix row count", kMaxRows));
  header.cols = static_cast<int>(in.readSize("the matrix column count", kMaxRows));
  return header;
}

Eigen::MatrixXd readDenseValues(TokenReader& in, const MatrixHeader& header) {
  // Storage 0 repeats the dimensions before the values.
  const long long rows = in.readSize("the dense matrix row count", kMaxRows);
  const long long cols = in.readSize("the dense matrix column count", kMaxRows);
  if (rows != header.rows || cols != header.cols)
    in.failHere("dense matrix is " + std::to_string(rows) + "x" + std::to_string(cols) +
                " but its header says " + std::to_string(header.rows) + "x" + std::to_string(header.cols));
  in.requireAvailable(rows * cols, "the dense matrix");
  Eigen::MatrixXd matrix(rows, cols);
  // Column-major: the file prints one column per line.
  for (long long c = 0; c < cols; ++c)
    for (long long r = 0; r < rows; ++r)
      matrix(r, c) = in.readDouble("matrix entry (" + std::to_string(r) + ", " + std::to_string(c) + ")");
  return matrix;
}

// Cumulative block ends (strictly increasing, last == total) as offsets starting at 0.
std::vector<int> readBlockEnds(TokenReader& in, long long count, int total, const char* what) {
  in.requireAvailable(count, what);
  std::vector<int> offset(1, 0);
  for (long long k = 0; k < count; ++k) {
    const long long end = in.readSize(what, kMaxRows);
    if (end <= offset.back())
      in.failHere(std::string(what) + " do not increase (" + std::to_string(end) + " after " +
                  std::to_string(offset.back()) + ")");
    offset.push_back(static_cast<int>(end));
  }
  if (offset.back() != total)
    in.failHere(std::string(what) + " end at " + std::to_string(offset.back()) + ", the matrix has " +
                std::to_string(total));
  return offset;
}

SiconosBlockMatrix readSparseBlockValues(TokenReader& in, const MatrixHeader& header) {
  SiconosBlockMatrix m;
  m.rows = header.rows;
  m.cols = header.cols;
  const long long block_count = in.readSize("the stored block count", kMaxRows * 64);
  const long long block_rows = in.readSize("the block row count", header.rows);
  const long long block_cols = in.readSize("the block column count", header.cols);
  m.row_offset = readBlockEnds(in, block_rows, header.rows, "block row ends");
  m.col_offset = readBlockEnds(in, block_cols, header.cols, "block column ends");

  const long long filled1 = in.readInt("filled1");
  const long long filled2 = in.readInt("filled2");
  if (filled1 != block_rows + 1)
    in.failHere("filled1 is " + std::to_string(filled1) + ", the block row count + 1 is " +
                std::to_string(block_rows + 1));
  if (filled2 != block_count)
    in.failHere("filled2 is " + std::to_string(filled2) + ", the stored block count is " +
                std::to_string(block_count));

  in.requireAvailable(filled1 + filled2, "the block index arrays");
  for (long long k = 0; k < filled1; ++k) {
    const long long start = in.readSize("block row pointer", block_count);
    if ((k == 0 && start != 0) || (k > 0 && start < m.row_start.back()))
      in.failHere("block row pointers must start at 0 and not decrease");
    m.row_start.push_back(static_cast<int>(start));
  }
  if (m.row_start.back() != block_count)
    in.failHere("block row pointers end at " + std::to_string(m.row_start.back()) +
                ", the stored block count is " + std::to_string(block_count));
  for (long long k = 0; k < filled2; ++k) {
    const long long col = in.readInt("block column index");
    if (col < 0 || col >= block_cols)
      in.failHere("block column index " + std::to_string(col) + " out of range (" +
                  std::to_string(block_cols) + " block columns)");
    m.block_col.push_back(static_cast<int>(col));
  }
  for (long long br = 0; br < block_rows; ++br) {
    std::vector<int> cols(m.block_col.begin() + m.row_start[br], m.block_col.begin() + m.row_start[br + 1]);
    std::sort(cols.begin(), cols.end());
    if (std::adjacent_find(cols.begin(), cols.end()) != cols.end())
      in.failHere("block row " + std::to_string(br) + " stores the same block column twice");
  }

  for (long long br = 0; br < block_rows; ++br) {
    const int rows = m.row_offset[br + 1] - m.row_offset[br];
    for (int k = m.row_start[br]; k < m.row_start[br + 1]; ++k) {
      const long long index = in.readInt("block index");
      if (index != k) in.failHere("block " + std::to_string(k) + " is labelled " + std::to_string(index));
      const int bc = m.block_col[k];
      const int cols = m.col_offset[bc + 1] - m.col_offset[bc];
      in.requireAvailable(static_cast<long long>(rows) * cols, "block " + std::to_string(k));
      Eigen::MatrixXd block(rows, cols);
      for (int c = 0; c < cols; ++c)  // column-major
        for (int r = 0; r < rows; ++r) block(r, c) = in.readDouble("a value of block " + std::to_string(k));
      m.blocks.push_back(std::move(block));
    }
  }
  return m;
}

Eigen::MatrixXd toDense(const SiconosBlockMatrix& m) {
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(m.rows, m.cols);
  for (std::size_t br = 0; br + 1 < m.row_offset.size(); ++br)
    for (int k = m.row_start[br]; k < m.row_start[br + 1]; ++k) {
      const int bc = m.block_col[k];
      dense.block(m.row_offset[br], m.col_offset[bc], m.blocks[k].rows(), m.blocks[k].cols()) = m.blocks[k];
    }
  return dense;
}

BlockSparseMatrix toContactBlocks(const SiconosBlockMatrix& m, int contacts) {
  ContactBlockBuilder builder(contacts);
  for (std::size_t br = 0; br + 1 < m.row_offset.size(); ++br)
    for (int k = m.row_start[br]; k < m.row_start[br + 1]; ++k) {
      const int row0 = m.row_offset[br];
      const int col0 = m.col_offset[m.block_col[k]];
      const Eigen::MatrixXd& block = m.blocks[k];
      for (int r = 0; r < block.rows(); ++r)
        for (int c = 0; c < block.cols(); ++c) builder.add(row0 + r, col0 + c, block(r, c));
    }
  return builder.build();
}

Eigen::VectorXd readVector(TokenReader& in, long long size, const char* name) {
  in.requireAvailable(size, name);
  Eigen::VectorXd v(size);
  for (long long i = 0; i < size; ++i)
    v[i] = in.readDouble(std::string(name) + "[" + std::to_string(i) + "]");
  return v;
}

void requireSquare(TokenReader& in, const MatrixHeader& header, long long rows) {
  if (header.rows != rows || header.cols != rows)
    in.failHere("the matrix is " + std::to_string(header.rows) + "x" + std::to_string(header.cols) + ", " +
                std::to_string(rows) + "x" + std::to_string(rows) + " expected");
}

Problem readLcp(TokenReader& in) {
  const long long n = in.readSize("the LCP size n", kMaxRows);
  const MatrixHeader header = readMatrixHeader(in);
  requireSquare(in, header, n);
  // LCPs are small; a dense M keeps them in the form makeLcpProblem takes. A dense file
  // is bounded by its own size, a sparse one is not: refuse to densify a huge one.
  if (header.storage == 1 && n > kMaxDenseLcpRows)
    in.failHere("sparse LCP of size " + std::to_string(n) + " is too large to convert to dense (at most " +
                std::to_string(kMaxDenseLcpRows) + ")");
  Eigen::MatrixXd M =
      header.storage == 0 ? readDenseValues(in, header) : toDense(readSparseBlockValues(in, header));
  const Eigen::VectorXd q = readVector(in, n, "q");
  return makeLcpProblem(M, q);
}

Problem readFc3d(TokenReader& in) {
  const long long dimension = in.readInt("the space dimension");
  if (dimension != 3) in.failHere("space dimension " + std::to_string(dimension) + ", 3 expected");
  const long long nc = in.readSize("the contact count", kMaxRows / 3);
  const MatrixHeader header = readMatrixHeader(in);
  requireSquare(in, header, 3 * nc);
  Problem problem;
  if (header.storage == 0) {
    problem.W = readDenseValues(in, header);
  } else {
    problem.W = toContactBlocks(readSparseBlockValues(in, header), static_cast<int>(nc));
  }
  problem.d_free = readVector(in, 3 * nc, "q");
  const Eigen::VectorXd mu = readVector(in, nc, "mu");
  problem.contacts.resize(nc);
  for (long long c = 0; c < nc; ++c) {
    if (mu[c] < 0.0) fail(in.path(), "mu[" + std::to_string(c) + "] is negative");
    problem.contacts[c].id = c;
    problem.contacts[c].type = ContactType::kFrictional;
    problem.contacts[c].rows = 3;
    problem.contacts[c].mu = mu[c];
  }
  return problem;
}

// The first numbers of a file (at most four; fewer where it ends or a token is not a number),
// read once to tell its kind: the full read reports any fault.
struct HeaderPeek {
  std::array<long long, 4> values{};
  int count = 0;
};
HeaderPeek peekHeader(const std::string& path, const std::string& content) {
  TokenReader peek(path, content.substr(0, 4096));  // the header is at the start
  HeaderPeek header;
  try {
    for (; header.count < 4; ++header.count) header.values[header.count] = peek.readInt("");
  } catch (const ProblemFileError&) {
  }
  return header;
}

bool isStorage(long long value) { return value == 0 || value == 1; }

// An FC3D file starts `3 nc storage rows`, with storage 0/1; an LCP file starts
// `n storage rows cols` with rows == n, so its third number is never 0 or 1 when n == 3.
bool looksLikeFc3d(const HeaderPeek& h) { return h.count >= 3 && h.values[0] == 3 && isStorage(h.values[2]); }

// A 2-D frictional contact file (Siconos' FC2D, `2 nc storage 2nc ...`) read as an LCP would be
// refused for its "matrix storage" nc: it is named instead. An LCP of size 2 has 2, not 0/1, third.
bool looksLikeFc2d(const HeaderPeek& h) {
  return h.count == 4 && h.values[0] == 2 && h.values[1] > 0 && isStorage(h.values[2]) &&
         h.values[3] == 2 * h.values[1];
}

// The .dat parser proper, on the file's content; `path` names it in messages.
Problem parseSiconosDat(const std::string& path, std::string content) {
  const HeaderPeek header = peekHeader(path, content);
  if (looksLikeFc2d(header))
    fail(path, "a 2-D frictional contact problem (space dimension 2): only 3-D contact problems and LCPs are read");
  const bool fc3d = looksLikeFc3d(header);
  TokenReader in(path, std::move(content));
  Problem problem = fc3d ? readFc3d(in) : readLcp(in);
  problem.name = baseName(path);
  requireValid(path, problem);
  return problem;  // anything after the data is allowed (Siconos appends solutions, notes)
}

}  // namespace

Problem readSiconosDat(const std::string& path) { return parseSiconosDat(path, readWholeFile(path)); }

Problem readSiconosDat(std::istream& stream, const std::string& name) {
  std::string content;
  char buffer[65536];
  while (stream.read(buffer, sizeof(buffer)) || stream.gcount() > 0) {
    if (content.size() + static_cast<std::size_t>(stream.gcount()) > kMaxFileBytes)
      fail(name, "input is too large (more than " + std::to_string(kMaxFileBytes) + " bytes)");
    content.append(buffer, static_cast<std::size_t>(stream.gcount()));
  }
  if (stream.bad()) fail(name, "read error");
  return parseSiconosDat(name, std::move(content));
}

}  // namespace lcp_contact_solver::core
