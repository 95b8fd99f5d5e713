// The two lane types the tile kernel is written for: Lanes1 (one double, any
// CPU) and Lanes8 (eight doubles in an AVX-512 register). The kernel is one
// template over them, so both compute every face by the same formula; a run
// uses one of them throughout, which keeps its results independent of how the
// grid is cut into tiles and shared among threads.
//
// They differ in arithmetic in two places. rsqrt: Lanes1 divides by sqrt,
// Lanes8 refines the hardware's 14-bit estimate by a series to the third
// order (within 1.4e-16 relative), which avoids the divider, the bottleneck of
// this kernel. fma: fused in Lanes8, two roundings in Lanes1 (which runs
// where the CPU may have no fused multiply-add).
// rsqrt_fast is for a factor that multiplies a result rather than cancels in a
// difference: Lanes8 takes one Newton step, within 6e-9 relative and above
// the exact value by rounding at most.
#pragma once

#include <cmath>
#include <cstdint>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace dpsm::simd {

// Asks the caches for the lines of count elements from p, to read or to write.
template <bool ForWriting, class T>
inline void prefetch(const T *p, int count) {
#if defined(__GNUC__) || defined(__clang__)
    constexpr int per_line = 64 / static_cast<int>(sizeof(T));
    for (int i = 0; i < count; i += per_line) __builtin_prefetch(p + i, ForWriting ? 1 : 0, 3);
    // The last line, which the steps above miss when p is not at a line's start.
    if (count > 0) __builtin_prefetch(p + count - 1, ForWriting ? 1 : 0, 3);
#else
    (void)p;
    (void)count;
#endif
}

struct Lanes1 {
    static constexpr int width = 1;
    using Mask = bool;
    double v;

    static Lanes1 broadcast(double x) { return {x}; }
    static Lanes1 load(const double *p) { return {*p}; }
    static Lanes1 load(const float *p) { return {static_cast<double>(*p)}; }
    void store(double *p) const { *p = v; }
    void store_where(double *p, Mask m) const {
        if (m) *p = v;
    }
    void store_where(float *p, Mask m) const {
        if (m) *p = static_cast<float>(v);
    }
    static Mask first_lanes(int n) { return n > 0; }
    static Mask kind_is(const std::uint8_t *p, std::uint8_t k) { return *p == k; }

    friend Lanes1 operator+(Lanes1 a, Lanes1 b) { return {a.v + b.v}; }
    friend Lanes1 operator-(Lanes1 a, Lanes1 b) { return {a.v - b.v}; }
    friend Lanes1 operator*(Lanes1 a, Lanes1 b) { return {a.v * b.v}; }
    friend Mask operator>(Lanes1 a, Lanes1 b) { return a.v > b.v; }
    friend Mask operator!=(Lanes1 a, Lanes1 b) { return a.v != b.v; }
    friend Lanes1 select(Mask m, Lanes1 a, Lanes1 b) { return m ? a : b; }
    // Not fused: the generic kernel runs on CPUs without FMA.
    friend Lanes1 fma(Lanes1 a, Lanes1 b, Lanes1 c) { return {a.v * b.v + c.v}; }
    friend Lanes1 fnma(Lanes1 a, Lanes1 b, Lanes1 c) { return {c.v - a.v * b.v}; }
    friend Lanes1 mul_where(Mask m, Lanes1 a, Lanes1 b) { return {m ? a.v * b.v : 0.0}; }
    friend Lanes1 max_where(Mask m, Lanes1 a, Lanes1 b) { return {m && b.v > a.v ? b.v : a.v}; }
    // [the last lane of prev, the first lanes of cur] and [the last lanes of cur, the first of next].
    static Lanes1 shift_west(Lanes1 prev, Lanes1) { return prev; }
    static Lanes1 shift_east(Lanes1, Lanes1 next) { return next; }
    friend Lanes1 rsqrt(Lanes1 a) { return {1.0 / std::sqrt(a.v)}; }
    friend Lanes1 rsqrt_fast(Lanes1 a) { return {1.0 / std::sqrt(a.v)}; }
    static Mask both(Mask a, Mask b) { return a && b; }
    static Mask either(Mask a, Mask b) { return a || b; }
    static Mask but_not(Mask a, Mask b) { return a && !b; }
    static unsigned bits(Mask m) { return m ? 1u : 0u; }
    static Mask from_bits(unsigned b) { return (b & 1u) != 0; }
    static double hmax(Lanes1 a) { return a.v; }
};

#if defined(__AVX512F__)
struct Lanes8 {
    static constexpr int width = 8;
    using Mask = __mmask8;
    __m512d v;

    static Lanes8 broadcast(double x) { return {_mm512_set1_pd(x)}; }
    static Lanes8 load(const double *p) { return {_mm512_loadu_pd(p)}; }
    static Lanes8 load(const float *p) { return {_mm512_cvtps_pd(_mm256_loadu_ps(p))}; }
    void store(double *p) const { _mm512_storeu_pd(p, v); }
    void store_where(double *p, Mask m) const { _mm512_mask_storeu_pd(p, m, v); }
    void store_where(float *p, Mask m) const { _mm256_mask_storeu_ps(p, m, _mm512_cvtpd_ps(v)); }
    static Mask first_lanes(int n) { return static_cast<Mask>(n >= 8 ? 0xFF : n <= 0 ? 0 : (1u << n) - 1u); }
    static Mask kind_is(const std::uint8_t *p, std::uint8_t k) {
        const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i *>(p));
        return static_cast<Mask>(_mm_cmpeq_epi8_mask(bytes, _mm_set1_epi8(static_cast<char>(k))) & 0xFF);
    }

    friend Lanes8 operator+(Lanes8 a, Lanes8 b) { return {_mm512_add_pd(a.v, b.v)}; }
    friend Lanes8 operator-(Lanes8 a, Lanes8 b) { return {_mm512_sub_pd(a.v, b.v)}; }
    friend Lanes8 operator*(Lanes8 a, Lanes8 b) { return {_mm512_mul_pd(a.v, b.v)}; }
    friend Mask operator>(Lanes8 a, Lanes8 b) { return _mm512_cmp_pd_mask(a.v, b.v, _CMP_GT_OQ); }
    friend Mask operator!=(Lanes8 a, Lanes8 b) { return _mm512_cmp_pd_mask(a.v, b.v, _CMP_NEQ_UQ); }
    friend Lanes8 select(Mask m, Lanes8 a, Lanes8 b) { return {_mm512_mask_blend_pd(m, b.v, a.v)}; }
    friend Lanes8 fma(Lanes8 a, Lanes8 b, Lanes8 c) { return {_mm512_fmadd_pd(a.v, b.v, c.v)}; }
    friend Lanes8 fnma(Lanes8 a, Lanes8 b, Lanes8 c) { return {_mm512_fnmadd_pd(a.v, b.v, c.v)}; }
    friend Lanes8 mul_where(Mask m, Lanes8 a, Lanes8 b) { return {_mm512_maskz_mul_pd(m, a.v, b.v)}; }
    friend Lanes8 max_where(Mask m, Lanes8 a, Lanes8 b) { return {_mm512_mask_max_pd(a.v, m, a.v, b.v)}; }
    static Lanes8 shift_west(Lanes8 prev, Lanes8 cur) {
        return {_mm512_castsi512_pd(_mm512_alignr_epi64(_mm512_castpd_si512(cur.v), _mm512_castpd_si512(prev.v), 7))};
    }
    static Lanes8 shift_east(Lanes8 cur, Lanes8 next) {
        return {_mm512_castsi512_pd(_mm512_alignr_epi64(_mm512_castpd_si512(next.v), _mm512_castpd_si512(cur.v), 1))};
    }
    // y0 (1 - e)^(-1/2) with e = 1 - a y0^2 and the series cut after e^3:
    // |e| < 2^-13, so what is cut is below 7e-17 relative.
    friend Lanes8 rsqrt(Lanes8 a) {
        const __m512d y = _mm512_rsqrt14_pd(a.v);
        const __m512d e = _mm512_fnmadd_pd(a.v, _mm512_mul_pd(y, y), _mm512_set1_pd(1.0));
        __m512d series = _mm512_fmadd_pd(e, _mm512_set1_pd(5.0 / 16.0), _mm512_set1_pd(3.0 / 8.0));
        series = _mm512_fmadd_pd(series, e, _mm512_set1_pd(0.5));
        return {_mm512_fmadd_pd(_mm512_mul_pd(y, e), series, y)};
    }
    friend Lanes8 rsqrt_fast(Lanes8 a) {
        const __m512d y = _mm512_rsqrt14_pd(a.v);
        const __m512d error = _mm512_fnmadd_pd(a.v, _mm512_mul_pd(y, y), _mm512_set1_pd(1.0));
        return {_mm512_fmadd_pd(_mm512_mul_pd(y, error), _mm512_set1_pd(0.5), y)};
    }
    static Mask both(Mask a, Mask b) { return static_cast<Mask>(a & b); }
    static Mask either(Mask a, Mask b) { return static_cast<Mask>(a | b); }
    static Mask but_not(Mask a, Mask b) { return static_cast<Mask>(a & ~b); }
    static unsigned bits(Mask m) { return m; }
    static Mask from_bits(unsigned b) { return static_cast<Mask>(b); }
    static double hmax(Lanes8 a) {
        alignas(64) double x[8];
        _mm512_store_pd(x, a.v);
        double m = x[0];
        for (int i = 1; i < 8; ++i) m = x[i] > m ? x[i] : m;
        return m;
    }
};
#endif

}  // namespace dpsm::simd
