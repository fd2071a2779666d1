// The fuzz targets as plain functions: each takes the fuzzer's bytes and returns "" or a
// sentence naming the broken invariant. The libFuzzer entry points (built with
// -DLCS_FUZZ=ON and clang, `make fuzz`) abort on a non-empty answer; test_fuzz_corpus runs
// every input kept under test/fuzz/corpus/ through the same functions in the normal build,
// so `make test` replays the corpus (and every crash input added to it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace lcs_fuzz {

// The bytes are a Siconos .dat file: readSiconosDat (stream overload) must return a valid
// problem or throw ProblemFileError, nothing else; a problem it returns is solved by every
// applicable solver (small caps) and the results must be finite and honest.
std::string datReaderOneInput(const std::uint8_t* data, std::size_t size);

// The bytes describe a ContactArray, a Compliance and solver parameters (fuzz_msg_solve.cpp):
// message → problem conversion (toProblem) + solve through the node's CycleSolver must
// reject or solve; what it publishes must be finite; two runs must agree bit for bit.
std::string msgSolveOneInput(const std::uint8_t* data, std::size_t size);

}  // namespace lcs_fuzz
