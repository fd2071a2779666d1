// Fuzz target: the Siconos .dat reader (readSiconosDat, stream overload) on arbitrary bytes,
// then every applicable solver on what it accepts. See fuzz_targets.h.
#include "fuzz_check.h"
#include "fuzz_targets.h"

#include "lcp_contact_solver/core/problem_io.h"

#include <cstdlib>
#include <exception>
#include <sstream>

namespace lcs_fuzz {

std::string datReaderOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream stream(std::string(reinterpret_cast<const char*>(data), size));
  lcs::core::Problem problem;
  try {
    problem = lcs::core::readSiconosDat(stream, "fuzz.dat");
  } catch (const lcs::core::ProblemFileError& e) {
    const std::string what = e.what();
    if (what.rfind("fuzz.dat: ", 0) != 0 || what.find('\n') != std::string::npos)
      return "reader error is not one line naming the input: " + what;
    return "";  // refused with a clear error: fine
  } catch (const std::exception& e) {
    return std::string("reader threw something other than ProblemFileError: ") + e.what();
  }
  if (const std::string fault = lcs::core::validateProblem(problem); !fault.empty())
    return "reader returned an invalid problem: " + fault;
  // Solve with small caps (the fuzzer must stay fast): every solver that takes the size.
  const int rows = problem.rowCount();
  for (lcs::core::SolverKind kind :
       {lcs::core::SolverKind::kAuto, lcs::core::SolverKind::kPgs, lcs::core::SolverKind::kNlgs,
        lcs::core::SolverKind::kLemke, lcs::core::SolverKind::kApgd, lcs::core::SolverKind::kNewton}) {
    if ((kind == lcs::core::SolverKind::kLemke || kind == lcs::core::SolverKind::kNewton) && rows > 300)
      continue;
    lcs::core::SolverParams params;
    params.solver = kind;
    params.maxIt = 30;
    params.tolerance = 1e-6;
    params.initial_guess = false;
    const lcs::core::SolveResult a = lcs::core::solveProblem(problem, params);
    if (std::string err = checkResult(problem, params, a); !err.empty())
      return std::string(lcs::core::solverName(kind)) + ": " + err;
    const lcs::core::SolveResult b = lcs::core::solveProblem(problem, params);
    if (std::string err = checkDeterministic(a, b); !err.empty())
      return std::string(lcs::core::solverName(kind)) + ": " + err;
  }
  return "";
}

}  // namespace lcs_fuzz

#ifdef LCS_LIBFUZZER
#include <cstdio>
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string fault = lcs_fuzz::datReaderOneInput(data, size);
  if (!fault.empty()) {
    std::fprintf(stderr, "fuzz_dat_reader: %s\n", fault.c_str());
    std::abort();
  }
  return 0;
}
#endif
