// lcp_solve: solves contact problem files from the command line (see problem_report.h).
#include "lcp_contact_solver/core/problem_report.h"

#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return lcp_contact_solver::runLcpSolve(args, std::cout, std::cerr);
}
