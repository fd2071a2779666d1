// Writes the small FCLIB files in this folder (fclib_*.hdf5) that test_problem_io reads.
// Not part of the build; the files are checked in. To regenerate, from this folder:
//   g++ -std=c++17 make_fclib_test_files.cpp -I/usr/include/hdf5/serial
//       -L/usr/lib/x86_64-linux-gnu/hdf5/serial -lfclib -lhdf5_hl -lhdf5 -o /tmp/make_fclib
//   /tmp/make_fclib
//
// Valid files are written with fclib_write_local itself, so the reader is tested on what
// FCLIB writes; the faulty ones are written dataset by dataset in FCLIB's layout with one
// fault each.
extern "C" {
#include <fclib.h>
}
#include <hdf5.h>
#include <hdf5_hl.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

// W(r, c) = 10 (r + 1) + (c + 1): non-symmetric, so a transposed read is caught.
double entry(int r, int c) { return 10.0 * (r + 1) + (c + 1); }

// Two contacts with contact-pair blocks (0,0), (0,1), (1,1) stored, (1,0) empty.
bool storedInTwoContactPattern(int r, int c) { return !(r / 3 == 1 && c / 3 == 0); }

struct Compressed {
  std::vector<int> p, i;
  std::vector<double> x;
};

// Compressed columns of the 6x6 two-contact W.
Compressed twoContactCsc() {
  Compressed w;
  w.p.push_back(0);
  for (int c = 0; c < 6; ++c) {
    for (int r = 0; r < 6; ++r)
      if (storedInTwoContactPattern(r, c)) {
        w.i.push_back(r);
        w.x.push_back(entry(r, c));
      }
    w.p.push_back(static_cast<int>(w.i.size()));
  }
  return w;
}

void writeWithFclib(const char* path, fclib_matrix* W, std::vector<double> q, std::vector<double> mu) {
  std::remove(path);
  char title[] = "lcp_contact_solver test problem";
  fclib_info info{title, nullptr, nullptr};
  fclib_local problem{};
  problem.W = W;
  problem.q = q.data();
  problem.mu = mu.data();
  problem.spacedim = 3;
  problem.info = &info;
  if (!fclib_write_local(&problem, path)) std::fprintf(stderr, "writing %s failed\n", path);
}

void writeValidCsc() {
  Compressed w = twoContactCsc();
  fclib_matrix W{};
  W.nzmax = static_cast<int>(w.x.size());
  W.m = W.n = 6;
  W.p = w.p.data();
  W.i = w.i.data();
  W.x = w.x.data();
  W.nz = -1;
  writeWithFclib("fclib_csc_2c.hdf5", &W, {-1, 0.1, 0.2, -2, 0.3, 0.4}, {0.3, 0.5});
}

void writeValidTriplet() {
  std::vector<int> rows, cols;
  std::vector<double> values;
  for (int k = 8; k >= 0; --k) {  // reverse order: the reader must not rely on sorting
    rows.push_back(k % 3);
    cols.push_back(k / 3);
    values.push_back(entry(k % 3, k / 3));
  }
  fclib_matrix W{};
  W.nzmax = W.nz = 9;
  W.m = W.n = 3;
  W.p = rows.data();
  W.i = cols.data();
  W.x = values.data();
  writeWithFclib("fclib_triplet_1c.hdf5", &W, {-1, 0.5, 0.25}, {0.4});
}

// The faults a hand-written file can carry.
enum class Fault { kMissingMu, kShortP, kGlobalOnly, kSpacedim2, kMixed, kBadIndex, kNanQ };

void intDataset(hid_t loc, const char* name, const std::vector<int>& v) {
  const hsize_t n = v.size();
  H5LTmake_dataset_int(loc, name, 1, &n, v.data());
}

void doubleDataset(hid_t loc, const char* name, const std::vector<double>& v) {
  const hsize_t n = v.size();
  H5LTmake_dataset_double(loc, name, 1, &n, v.data());
}

void writeFaulty(const char* path, Fault fault) {
  const hid_t file = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const char* root = fault == Fault::kGlobalOnly ? "/fclib_global" : "/fclib_local";
  const hid_t top = H5Gcreate2(file, root, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  intDataset(top, "spacedim", {fault == Fault::kSpacedim2 ? 2 : 3});

  Compressed w = twoContactCsc();
  if (fault == Fault::kShortP) w.p.pop_back();
  if (fault == Fault::kBadIndex) w.i[1] = 7;
  const hid_t W = H5Gcreate2(top, "W", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  intDataset(W, "nzmax", {static_cast<int>(w.x.size())});
  intDataset(W, "m", {6});
  intDataset(W, "n", {6});
  intDataset(W, "nz", {-1});
  intDataset(W, "p", w.p);
  intDataset(W, "i", w.i);
  doubleDataset(W, "x", w.x);
  H5Gclose(W);
  if (fault == Fault::kMixed) H5Gclose(H5Gcreate2(top, "V", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));

  const hid_t vectors = H5Gcreate2(top, "vectors", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  std::vector<double> q = {-1, 0.1, 0.2, -2, 0.3, 0.4};
  if (fault == Fault::kNanQ) q[4] = std::nan("");
  doubleDataset(vectors, "q", q);
  if (fault != Fault::kMissingMu) doubleDataset(vectors, "mu", {0.3, 0.5});
  H5Gclose(vectors);
  H5Gclose(top);
  H5Fclose(file);
}

}  // namespace

int main() {
  writeValidCsc();
  writeValidTriplet();
  writeFaulty("fclib_missing_mu.hdf5", Fault::kMissingMu);
  writeFaulty("fclib_short_p.hdf5", Fault::kShortP);
  writeFaulty("fclib_global_only.hdf5", Fault::kGlobalOnly);
  writeFaulty("fclib_spacedim2.hdf5", Fault::kSpacedim2);
  writeFaulty("fclib_mixed.hdf5", Fault::kMixed);
  writeFaulty("fclib_bad_index.hdf5", Fault::kBadIndex);
  writeFaulty("fclib_nan_q.hdf5", Fault::kNanQ);
  return 0;
}
