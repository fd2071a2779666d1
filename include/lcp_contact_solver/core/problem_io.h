// Readers for problems written by others: the Siconos numerics text format (.dat, LCP and
// 3D frictional contact, dense and sparse-block storage) and FCLIB's HDF5 (.hdf5).
#pragma once

#include "lcp_contact_solver/core/problem.h"

#include <istream>
#include <stdexcept>
#include <string>

namespace lcp_contact_solver::core {

// Thrown with a one-line message naming the file and the fault.
class ProblemFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Siconos .dat: an LCP (`n`, matrix, q) becomes n frictionless contacts; an FC3D file
// (`3`, nc, matrix, q, mu) becomes nc frictional contacts with their own μ. Dense storage
// gives a dense W, sparse-block storage a BlockSparseMatrix.
Problem readSiconosDat(const std::string& path);
// The same from a stream (a pipe, a string in memory, the fuzzer's bytes); `name` stands for
// the path in messages and in Problem::name. Reads at most 2 GiB.
Problem readSiconosDat(std::istream& stream, const std::string& name);

// FCLIB local problem (fclib_read_local) in 3D: frictional contacts with their own μ.
Problem readFclibHdf5(const std::string& path);

// Dispatches on the content (HDF5 signature) rather than the extension.
Problem readProblemFile(const std::string& path);

}  // namespace lcp_contact_solver::core
