// PCG32 (O'Neill 2014) and a hash to seed it from (seed, directions), so that every
// stochastic estimate is repeatable for the same inputs.
#pragma once
#include <cstdint>
#include <cstring>
#include "vector.h"

namespace bsdflab {

class PCG32 {
  public:
    explicit PCG32(uint64_t seed, uint64_t stream = 0xda3e39cb94b95bdbULL) {
        inc_ = (stream << 1u) | 1u;
        state_ = 0;
        next();
        state_ += seed;
        next();
    }
    uint32_t next() {
        uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // Uniform double in [0, 1) with 32 random bits.
    double uniform() { return next() * 0x1p-32; }

  private:
    uint64_t state_, inc_;
};

// splitmix64 finaliser: a well-mixed 64-bit hash step.
inline uint64_t mix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

inline uint64_t hash_double(uint64_t h, double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return mix64(h ^ bits);
}

inline uint64_t hash_directions(uint64_t seed, const Vec3 &a, const Vec3 &b) {
    uint64_t h = mix64(seed);
    for (double v : {a.x, a.y, a.z, b.x, b.y, b.z}) h = hash_double(h, v);
    return h;
}

} // namespace bsdflab
