// Reads the fuzz targets' inputs field by field: each get<T>() takes the next sizeof(T) bytes
// (zero-filled past the end of the input), so any byte string decodes to some input.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace ladar_perception {
namespace fuzz {

struct Reader {
  const uint8_t* p;
  size_t n;
  template <typename T>
  T get() {
    T v{};
    const size_t k = n < sizeof(T) ? n : sizeof(T);
    std::memcpy(&v, p, k);
    p += k;
    n -= k;
    return v;
  }
};

}  // namespace fuzz
}  // namespace ladar_perception
