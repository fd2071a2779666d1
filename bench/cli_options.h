// The benchmarks' command lines, on CLI11 like the tools: comma lists of integers, and one way
// to end on a bad argument (CLI11's message, exit status 2).
#pragma once

#include "timing_util.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace lcs_bench {

// `name` takes a comma list ("2,5,16"; "" is an empty list) into `values`; `shown` is the
// default as --help prints it.
inline CLI::Option* addIntListOption(CLI::App& app, const std::string& name, std::vector<int>* values,
                                     const std::string& doc, const std::string& shown) {
  return app
      .add_option_function<std::string>(
          name,
          [name, values](const std::string& text) {
            try {
              *values = parseIntList(text);
            } catch (const std::exception&) {
              throw CLI::ValidationError(name, "'" + text + "' is not a comma list of integers");
            }
          },
          doc)
      ->default_str(shown);
}

// Parses argv: -1 to go on, 0 after --help, 2 on a bad argument.
inline int parseArguments(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return -1;
}

}  // namespace lcs_bench
