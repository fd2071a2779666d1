// Reads structured values from a fuzzer's bytes, deterministically; past the end every read
// gives zero, so any byte string is a valid input. Shared by the fuzz targets and by the
// corpus replay test (test_fuzz_corpus), so a crash input replays the same way in both.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

namespace lcs_fuzz {

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - pos_; }

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  bool flag() { return (byte() & 1) != 0; }
  // Uniform-ish in [0, n) (n <= 256).
  int below(int n) { return n <= 1 ? 0 : byte() % n; }

  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | byte();
    return v;
  }

  // A double that favours the values that break numerical code: zeros, signs, tiny and
  // huge magnitudes, denormals, NaN and infinities, exact small integers; otherwise eight
  // raw bytes (any bit pattern, NaN payloads included).
  double number() {
    switch (byte() % 24) {
      case 0: return 0.0;
      case 1: return -0.0;
      case 2: return 1.0;
      case 3: return -1.0;
      case 4: return 0.5;
      case 5: return 1e-12;
      case 6: return -1e-3;
      case 7: return 1e300;
      case 8: return -1e300;
      case 9: return std::numeric_limits<double>::denorm_min();
      case 10: return std::numeric_limits<double>::quiet_NaN();
      case 11: return std::numeric_limits<double>::infinity();
      case 12: return -std::numeric_limits<double>::infinity();
      case 13: return std::numeric_limits<double>::max();
      case 14: return std::numeric_limits<double>::min();
      case 15: return 1e-300;
      case 16: {
        const std::uint64_t bits = u64();
        double v;
        std::memcpy(&v, &bits, sizeof(v));
        return v;
      }
      default:  // a moderate value: (byte - 128) / 16 scaled by a power of ten in 1e-6..1e6
        return (static_cast<int>(byte()) - 128) / 16.0 * std::pow(10.0, below(13) - 6);
    }
  }

  // A moderate finite value (for sizes of a well-formed problem): -8..8 in steps of 1/16.
  double moderate() { return (static_cast<int>(byte()) - 128) / 16.0; }

  std::string rest() {
    std::string s(reinterpret_cast<const char*>(data_ + pos_), size_ - pos_);
    pos_ = size_;
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace lcs_fuzz
