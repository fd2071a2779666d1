#include "lcp_contact_solver/core/problem_io.h"

extern "C" {
#include <fclib.h>
}
#include <hdf5.h>  // to check a file before fclib reads it, and to keep HDF5 quiet

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

// Larger problems are refused before anything is allocated for them: a corrupt or hostile
// header must not make us try to allocate terabytes.
constexpr long long kMaxRows = 1000000;
// Sparse-block LCPs are converted to a dense M; larger ones are refused (8 n² bytes).
constexpr long long kMaxDenseLcpRows = 8192;
// Larger files are refused before reading them into memory.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 31;
constexpr char kHdf5Signature[] = "\x89HDF\r\n\x1a\n";
constexpr std::size_t kHdf5SignatureSize = 8;

[[noreturn]] void fail(const std::string& path, const std::string& fault) {
  throw ProblemFileError(path + ": " + fault);
}

std::string baseName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

// A token as it may appear in a one-line message: printable, short.
std::string printable(std::string_view token) {
  constexpr std::size_t kMaxShown = 24;
  std::string shown;
  for (char ch : token.substr(0, kMaxShown))
    shown += std::isprint(static_cast<unsigned char>(ch)) ? ch : '?';
  if (token.size() > kMaxShown) shown += "...";
  return shown;
}

// Checks the file can be read and is not absurdly large; throws otherwise.
void checkReadableFile(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail(path, "cannot open file (no such file)");
  if (std::filesystem::is_directory(status)) fail(path, "cannot read: is a directory");
  if (std::filesystem::is_regular_file(status)) {
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxFileBytes)
      fail(path, "file is too large (" + std::to_string(size) + " bytes)");
  }
}

std::string readWholeFile(const std::string& path) {
  checkReadableFile(path);
  std::ifstream file(path, std::ios::binary);
  if (!file) fail(path, std::string("cannot open file (") + std::strerror(errno) + ")");
  std::ostringstream content;
  content << file.rdbuf();
  if (file.bad()) fail(path, "read error");
  return content.str();
}

// HDF5 puts its signature at offset 0, or after a user block at 512, 1024, 2048, ...
bool hasHdf5Signature(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  for (std::streamoff offset = 0; file; offset = offset == 0 ? 512 : 2 * offset) {
    char head[kHdf5SignatureSize] = {};
    if (!file.seekg(offset) || !file.read(head, kHdf5SignatureSize)) return false;
    if (std::memcmp(head, kHdf5Signature, kHdf5SignatureSize) == 0) return true;
  }
  return false;
}

// ---- Siconos .dat -------------------------------------------------------------------------

// Reads whitespace-separated numbers one by one, remembering the line for messages.
class TokenReader {
 public:
  TokenReader(std::string path, std::string content)
      : path_(std::move(path)), content_(std::move(content)) {}

  const std::string& path() const { return path_; }

  [[noreturn]] void failHere(const std::string& fault) const {
    fail(path_, "line " + std::to_string(line_) + ": " + fault);
  }

  // A non-negative integer no larger than `max`.
  long long readSize(const std::string& what, long long max) {
    const long long value = readInt(what);
    if (value < 0) failHere(what + " is negative (" + std::to_string(value) + ")");
    if (value > max)
      failHere(what + " is too large (" + std::to_string(value) + ", at most " +
               std::to_string(max) + " allowed)");
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
      fail(path_, "truncated: " + what + " needs " + std::to_string(count) +
                      " numbers but only " + std::to_string(bytes_left) + " bytes remain");
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
    in.failHere("unknown matrix storage " + std::to_string(storage) +
                " (0 dense, 1 sparse block expected)");
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
                " but its header says " + std::to_string(header.rows) + "x" +
                std::to_string(header.cols));
  in.requireAvailable(rows * cols, "the dense matrix");
  Eigen::MatrixXd matrix(rows, cols);
  // Column-major: the file prints one column per line.
  for (long long c = 0; c < cols; ++c)
    for (long long r = 0; r < rows; ++r)
      matrix(r, c) = in.readDouble("matrix entry (" + std::to_string(r) + ", " +
                                   std::to_string(c) + ")");
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
    in.failHere(std::string(what) + " end at " + std::to_string(offset.back()) +
                ", the matrix has " + std::to_string(total));
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
    std::vector<int> cols(m.block_col.begin() + m.row_start[br],
                          m.block_col.begin() + m.row_start[br + 1]);
    std::sort(cols.begin(), cols.end());
    if (std::adjacent_find(cols.begin(), cols.end()) != cols.end())
      in.failHere("block row " + std::to_string(br) + " stores the same block column twice");
  }

  for (long long br = 0; br < block_rows; ++br) {
    const int rows = m.row_offset[br + 1] - m.row_offset[br];
    for (int k = m.row_start[br]; k < m.row_start[br + 1]; ++k) {
      const long long index = in.readInt("block index");
      if (index != k)
        in.failHere("block " + std::to_string(k) + " is labelled " + std::to_string(index));
      const int bc = m.block_col[k];
      const int cols = m.col_offset[bc + 1] - m.col_offset[bc];
      in.requireAvailable(static_cast<long long>(rows) * cols, "block " + std::to_string(k));
      Eigen::MatrixXd block(rows, cols);
      for (int c = 0; c < cols; ++c)  // column-major
        for (int r = 0; r < rows; ++r)
          block(r, c) = in.readDouble("a value of block " + std::to_string(k));
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
      dense.block(m.row_offset[br], m.col_offset[bc], m.blocks[k].rows(), m.blocks[k].cols()) =
          m.blocks[k];
    }
  return dense;
}

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
    in.failHere("the matrix is " + std::to_string(header.rows) + "x" +
                std::to_string(header.cols) + ", " + std::to_string(rows) + "x" +
                std::to_string(rows) + " expected");
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
  Eigen::MatrixXd M = header.storage == 0 ? readDenseValues(in, header)
                                          : toDense(readSparseBlockValues(in, header));
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

// An FC3D file starts `3 nc storage rows`, with storage 0/1; an LCP file starts
// `n storage rows cols` with rows == n, so its third number is never 0 or 1 when n == 3.
bool looksLikeFc3d(const std::string& path, const std::string& content) {
  TokenReader peek(path, content.substr(0, 4096));  // the header is at the start
  try {
    if (peek.readInt("") != 3) return false;
    peek.readInt("");
    const long long storage = peek.readInt("");
    return storage == 0 || storage == 1;
  } catch (const ProblemFileError&) {
    return false;  // the full read reports the fault
  }
}

void requireValid(const std::string& path, const Problem& problem) {
  if (const std::string fault = validateProblem(problem, kMaxRows); !fault.empty())
    fail(path, fault);
}

// ---- FCLIB .hdf5 --------------------------------------------------------------------------

// HDF5 prints a stack of diagnostics on stderr for every failed call (a corrupt or
// truncated file); we report one line ourselves instead. Restores the previous handler.
class QuietHdf5Errors {
 public:
  QuietHdf5Errors() {
    H5Eget_auto2(H5E_DEFAULT, &handler_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, handler_, data_); }
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

 private:
  H5E_auto2_t handler_ = nullptr;
  void* data_ = nullptr;
};

// fclib_delete_local frees the members but not the struct itself (LeakSanitizer shows it).
struct FclibLocalDeleter {
  void operator()(fclib_local* problem) const {
    fclib_delete_local(problem);
    std::free(problem);
  }
};

// An HDF5 identifier closed on scope exit.
class Hdf5Id {
 public:
  Hdf5Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hdf5Id() {
    if (id_ >= 0) close_(id_);
  }
  Hdf5Id(const Hdf5Id&) = delete;
  Hdf5Id& operator=(const Hdf5Id&) = delete;
  bool valid() const { return id_ >= 0; }
  hid_t get() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// fclib_read_local calls exit(1) when an object it expects is missing or unreadable, and
// reads each dataset whole into a buffer sized from the matrix header, so an inconsistent
// file would end the process or overflow. This checks, with quiet HDF5 calls, everything
// fclib_read_local will read before it is called. Call inside QuietHdf5Errors.
class FclibPreflight {
 public:
  FclibPreflight(const std::string& path, hid_t file) : path_(path), file_(file) {}

  void run() {
    if (exists("/fclib_global") && !exists("/fclib_local"))
      fail(path_, "FCLIB global problem (fclib_global); only local problems are supported");
    if (!exists("/fclib_local")) fail(path_, "not an FCLIB local problem (no /fclib_local group)");
    if (exists("/fclib_local/V") || exists("/fclib_local/R"))
      fail(path_, "FCLIB mixed problems (V, R) are not supported");
    const int spacedim = readScalarInt("/fclib_local/spacedim");
    if (spacedim != 3)
      fail(path_, "FCLIB problem in dimension " + std::to_string(spacedim) + ", only 3 is supported");
    const int rows = checkMatrix("/fclib_local/W");
    requireDataset("/fclib_local/vectors/q", H5T_FLOAT, rows);
    requireDataset("/fclib_local/vectors/mu", H5T_FLOAT, rows / 3);
    if (exists("/fclib_local/info"))
      for (const char* text : {"title", "description", "math_info"})
        optionalString(std::string("/fclib_local/info/") + text);
  }

 private:
  // True if every component of the absolute `name` exists.
  bool exists(const std::string& name) const {
    for (std::size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
      const std::string prefix = name.substr(0, slash);
      if (H5Lexists(file_, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
      if (slash == std::string::npos) return true;
    }
  }

  // Checks a dataset's type class and element count; returns its element count.
  long long requireDataset(const std::string& name, H5T_class_t type_class, long long points = -1) const {
    if (!exists(name)) fail(path_, "FCLIB file lacks " + name);
    const Hdf5Id dataset(H5Dopen2(file_, name.c_str(), H5P_DEFAULT), H5Dclose);
    if (!dataset.valid()) fail(path_, name + " is not a readable dataset");
    const Hdf5Id type(H5Dget_type(dataset.get()), H5Tclose);
    const Hdf5Id space(H5Dget_space(dataset.get()), H5Sclose);
    if (!type.valid() || !space.valid()) fail(path_, name + " is not a readable dataset");
    const H5T_class_t actual_class = H5Tget_class(type.get());
    if (actual_class != type_class) fail(path_, name + " has the wrong element type");
    if (type_class == H5T_STRING && H5Tis_variable_str(type.get()) != 0)
      fail(path_, name + " is a variable-length string");
    const long long actual_points = H5Sget_simple_extent_npoints(space.get());
    if (actual_points < 0) fail(path_, name + " has an unreadable size");
    if (points >= 0 && actual_points != points)
      fail(path_, name + " has " + std::to_string(actual_points) + " entries, " +
                      std::to_string(points) + " expected");
    return actual_points;
  }

  int readScalarInt(const std::string& name) const {
    requireDataset(name, H5T_INTEGER, 1);
    const Hdf5Id dataset(H5Dopen2(file_, name.c_str(), H5P_DEFAULT), H5Dclose);
    int value = 0;
    if (H5Dread(dataset.get(), H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value) < 0)
      fail(path_, "cannot read " + name);
    return value;
  }

  void optionalString(const std::string& name) const {
    if (exists(name)) requireDataset(name, H5T_STRING, 1);
  }

  // Checks a matrix group as fclib's reader will read it; returns its row count.
  int checkMatrix(const std::string& group) const {
    const int nzmax = readScalarInt(group + "/nzmax");
    const int m = readScalarInt(group + "/m");
    const int n = readScalarInt(group + "/n");
    const int nz = readScalarInt(group + "/nz");
    if (m <= 0 || n <= 0 || m > kMaxRows || n > kMaxRows)
      fail(path_, group + " is " + std::to_string(m) + "x" + std::to_string(n) +
                      ", sizes must be in 1.." + std::to_string(kMaxRows));
    if (m != n) fail(path_, group + " is not square (" + std::to_string(m) + "x" + std::to_string(n) + ")");
    if (m % 3 != 0) fail(path_, group + " has " + std::to_string(m) + " rows, not a multiple of 3");
    if (nzmax < 0 || static_cast<long long>(nzmax) > static_cast<long long>(m) * n)
      fail(path_, group + " has an impossible capacity nzmax = " + std::to_string(nzmax));
    if (nz >= 0) {  // triplet
      if (nz > nzmax) fail(path_, group + " has more triplets than its capacity");
      requireDataset(group + "/p", H5T_INTEGER, nz);
      requireDataset(group + "/i", H5T_INTEGER, nz);
      const long long values = requireDataset(group + "/x", H5T_FLOAT);
      if (values < nz || values > nzmax) fail(path_, group + "/x has the wrong number of entries");
    } else if (nz == -1 || nz == -2) {  // compressed column / row
      requireDataset(group + "/p", H5T_INTEGER, (nz == -1 ? n : m) + 1LL);
      requireDataset(group + "/i", H5T_INTEGER, nzmax);
      requireDataset(group + "/x", H5T_FLOAT, nzmax);
    } else {
      fail(path_, group + " has an unknown storage (nz = " + std::to_string(nz) + ")");
    }
    if (exists(group + "/conditioning")) {  // optional matrix information
      optionalString(group + "/comment");
      requireDataset(group + "/conditioning", H5T_FLOAT, 1);
      requireDataset(group + "/determinant", H5T_FLOAT, 1);
      requireDataset(group + "/rank", H5T_INTEGER, 1);
    }
    return m;
  }

  const std::string& path_;
  hid_t file_;
};

void preflightFclib(const std::string& path) {
  const Hdf5Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.valid()) fail(path, "HDF5 cannot open the file (corrupt or truncated?)");
  FclibPreflight(path, file.get()).run();
}

// Visits every stored entry of an fclib_matrix (compressed column, compressed row or
// triplet) after checking its index arrays.
template <typename Visit>
void forEachEntry(const std::string& path, const fclib_matrix& W, Visit visit) {
  if (!W.p || !W.i || !W.x) fail(path, "W has no index or value arrays");
  if (W.nz >= 0) {  // triplet: p holds row indices, i column indices
    if (W.nz > W.nzmax) fail(path, "W has more triplets than its capacity");
    for (int k = 0; k < W.nz; ++k) {
      if (W.p[k] < 0 || W.p[k] >= W.m || W.i[k] < 0 || W.i[k] >= W.n)
        fail(path, "W triplet " + std::to_string(k) + " is out of range");
      visit(W.p[k], W.i[k], W.x[k]);
    }
    return;
  }
  if (W.nz != -1 && W.nz != -2) fail(path, "W has an unknown storage (nz = " + std::to_string(W.nz) + ")");
  const bool by_column = W.nz == -1;
  const int outer = by_column ? W.n : W.m;
  const int inner = by_column ? W.m : W.n;
  if (W.p[0] != 0 || W.p[outer] > W.nzmax || W.p[outer] < 0)
    fail(path, "W's compressed pointers are inconsistent");
  for (int o = 0; o < outer; ++o) {
    if (W.p[o + 1] < W.p[o]) fail(path, "W's compressed pointers decrease");
    for (int k = W.p[o]; k < W.p[o + 1]; ++k) {
      const int in = W.i[k];
      if (in < 0 || in >= inner) fail(path, "W index " + std::to_string(in) + " is out of range");
      if (by_column) visit(in, o, W.x[k]); else visit(o, in, W.x[k]);
    }
  }
}

Problem fromFclib(const std::string& path, const fclib_local& local) {
  if (local.spacedim != 3)
    fail(path, "FCLIB problem in dimension " + std::to_string(local.spacedim) + ", only 3 is supported");
  if (local.V || local.R)
    fail(path, "FCLIB mixed problems (V, R) are not supported");
  if (!local.W || !local.q || !local.mu) fail(path, "FCLIB problem lacks W, q or mu");
  const fclib_matrix& W = *local.W;
  if (W.m != W.n) fail(path, "W is not square (" + std::to_string(W.m) + "x" + std::to_string(W.n) + ")");
  if (W.m <= 0 || W.m % 3 != 0) fail(path, "W has " + std::to_string(W.m) + " rows, a positive multiple of 3 expected");
  if (W.m > kMaxRows) fail(path, "W has " + std::to_string(W.m) + " rows, too many");
  if (W.nzmax < 0) fail(path, "W has a negative capacity");

  const int nc = W.m / 3;
  ContactBlockBuilder builder(nc);
  forEachEntry(path, W, [&](int row, int col, double value) {
    if (!std::isfinite(value)) fail(path, "W holds a non-finite value");
    builder.add(row, col, value);
  });

  Problem problem;
  problem.W = builder.build();
  problem.d_free = Eigen::Map<const Eigen::VectorXd>(local.q, W.m);
  if (!problem.d_free.allFinite()) fail(path, "q holds a non-finite value");
  problem.contacts.resize(nc);
  for (int c = 0; c < nc; ++c) {
    if (!std::isfinite(local.mu[c]) || local.mu[c] < 0.0)
      fail(path, "mu[" + std::to_string(c) + "] is negative or not finite");
    problem.contacts[c].id = c;
    problem.contacts[c].type = ContactType::kFrictional;
    problem.contacts[c].rows = 3;
    problem.contacts[c].mu = local.mu[c];
  }
  return problem;
}

}  // namespace

namespace {

// The .dat parser proper, on the file's content; `path` names it in messages.
Problem parseSiconosDat(const std::string& path, std::string content) {
  const bool fc3d = looksLikeFc3d(path, content);
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

Problem readFclibHdf5(const std::string& path) {
  checkReadableFile(path);
  // fclib prints HDF5 diagnostics on stderr for non-HDF5 files; check ourselves first.
  if (!hasHdf5Signature(path)) fail(path, "not an HDF5 file (no HDF5 signature)");
  std::unique_ptr<fclib_local, FclibLocalDeleter> local;
  {
    const QuietHdf5Errors quiet;
    preflightFclib(path);
    local.reset(fclib_read_local(path.c_str()));
  }
  if (!local) fail(path, "FCLIB could not read a local frictional contact problem (corrupt file?)");
  Problem problem = fromFclib(path, *local);
  problem.name = baseName(path);
  requireValid(path, problem);
  return problem;
}

Problem readProblemFile(const std::string& path) {
  checkReadableFile(path);
  return hasHdf5Signature(path) ? readFclibHdf5(path) : readSiconosDat(path);
}

}  // namespace lcp_contact_solver::core
