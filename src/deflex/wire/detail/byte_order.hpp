// Fixed-size fields in a stated byte order, assembled byte by byte (never by casting a struct onto
// the buffer, so neither the host's order nor its alignment matters). The controllers' formats
// disagree: FANUC's Stream Motion and UR's RTDE are big-endian, MotoROS2's real-time packets
// little-endian. Nothing here allocates or throws.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace deflex::wire_bytes {

enum class Order { kBig, kLittle };

template <typename U>
[[nodiscard]] inline U load(Order order, const unsigned char* p) noexcept {
  U v = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i) {
    const std::size_t at = order == Order::kBig ? i : sizeof(U) - 1 - i;
    v = static_cast<U>(v << 8U | static_cast<U>(p[at]));
  }
  return v;
}

template <typename U>
inline void store(Order order, U v, unsigned char* p) noexcept {
  for (std::size_t i = 0; i < sizeof(U); ++i) {
    const std::size_t at = order == Order::kBig ? sizeof(U) - 1 - i : i;
    p[at] = static_cast<unsigned char>(v & 0xffU);
    v = static_cast<U>(v >> 8U);
  }
}

[[nodiscard]] inline std::uint16_t load_u16(Order o, const unsigned char* p) noexcept {
  return load<std::uint16_t>(o, p);
}
[[nodiscard]] inline std::uint32_t load_u32(Order o, const unsigned char* p) noexcept {
  return load<std::uint32_t>(o, p);
}
[[nodiscard]] inline std::int32_t load_i32(Order o, const unsigned char* p) noexcept {
  return std::bit_cast<std::int32_t>(load<std::uint32_t>(o, p));
}
[[nodiscard]] inline std::uint64_t load_u64(Order o, const unsigned char* p) noexcept {
  return load<std::uint64_t>(o, p);
}
[[nodiscard]] inline float load_f32(Order o, const unsigned char* p) noexcept {
  return std::bit_cast<float>(load<std::uint32_t>(o, p));
}
[[nodiscard]] inline double load_f64(Order o, const unsigned char* p) noexcept {
  return std::bit_cast<double>(load<std::uint64_t>(o, p));
}

inline void store_u16(Order o, std::uint16_t v, unsigned char* p) noexcept { store(o, v, p); }
inline void store_u32(Order o, std::uint32_t v, unsigned char* p) noexcept { store(o, v, p); }
inline void store_i32(Order o, std::int32_t v, unsigned char* p) noexcept {
  store(o, std::bit_cast<std::uint32_t>(v), p);
}
inline void store_u64(Order o, std::uint64_t v, unsigned char* p) noexcept { store(o, v, p); }
inline void store_f32(Order o, float v, unsigned char* p) noexcept { store(o, std::bit_cast<std::uint32_t>(v), p); }
inline void store_f64(Order o, double v, unsigned char* p) noexcept { store(o, std::bit_cast<std::uint64_t>(v), p); }

}  // namespace deflex::wire_bytes
