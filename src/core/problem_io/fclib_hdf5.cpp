// FCLIB .hdf5 files (local frictional contact problems), read into a Problem.
#include "problem_files.h"

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

using namespace problem_files;

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
      fail(path_, name + " has " + std::to_string(actual_points) + " entries, " + std::to_string(points) +
                      " expected");
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
      fail(path_, group + " is " + std::to_string(m) + "x" + std::to_string(n) + ", sizes must be in 1.." +
                      std::to_string(kMaxRows));
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
      if (by_column)
        visit(in, o, W.x[k]);
      else
        visit(o, in, W.x[k]);
    }
  }
}

Problem fromFclib(const std::string& path, const fclib_local& local) {
  if (local.spacedim != 3)
    fail(path, "FCLIB problem in dimension " + std::to_string(local.spacedim) + ", only 3 is supported");
  if (local.V || local.R) fail(path, "FCLIB mixed problems (V, R) are not supported");
  if (!local.W || !local.q || !local.mu) fail(path, "FCLIB problem lacks W, q or mu");
  const fclib_matrix& W = *local.W;
  if (W.m != W.n) fail(path, "W is not square (" + std::to_string(W.m) + "x" + std::to_string(W.n) + ")");
  if (W.m <= 0 || W.m % 3 != 0)
    fail(path, "W has " + std::to_string(W.m) + " rows, a positive multiple of 3 expected");
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

}  // namespace lcp_contact_solver::core
