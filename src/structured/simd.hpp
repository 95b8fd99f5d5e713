// The lane types the tile kernel is written for: Lanes1 (one double, any
// CPU), Lanes4 (four doubles in an AVX2 register) and Lanes8 (eight doubles
// in an AVX-512 register). The kernel is one template over them, so all
// compute every face by the same formula; a run uses one of them throughout,
// which keeps its results independent of how the grid is cut into tiles and
// shared among threads.
//
// max(a, b) is a > b ? a : b and min(a, b) a < b ? a : b, lane by lane, as
// the x86 instructions are (so the lanes agree where a zero's sign or a NaN
// would tell them apart).
//
// They differ in arithmetic in two places. rsqrt: Lanes1 and Lanes4 divide
// by sqrt; Lanes8 refines the hardware's 14-bit estimate by a series to the
// third order (within 1.4e-16 relative), which avoids the divider, the
// bottleneck of this kernel. rsqrt_fast is for a factor that multiplies a
// result rather than cancels in a difference: Lanes8 takes one Newton step,
// within 6e-9 relative and above the exact value by rounding at most. fma:
// fused in Lanes4 and Lanes8, two roundings in Lanes1 (which runs where the
// CPU may have no fused multiply-add).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__AVX512F__) || defined(__AVX2__)
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

// The largest of a vector's lanes, stored.
template <int N>
inline double largest_of(const double (&x)[N]) {
    double m = x[0];
    for (int i = 1; i < N; ++i) m = x[i] > m ? x[i] : m;
    return m;
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
    friend Lanes1 sqrt(Lanes1 a) { return {std::sqrt(a.v)}; }
    friend Lanes1 operator/(Lanes1 a, Lanes1 b) { return {a.v / b.v}; }
    friend Lanes1 mantissa_exponent(Lanes1 x, Lanes1 &e) {
        int exponent = 0;
        const double half_mantissa = std::frexp(x.v, &exponent);  // in [1/2, 1)
        e = {static_cast<double>(exponent - 1)};
        return {2.0 * half_mantissa};
    }
    friend Lanes1 scale_by_power_of_two(Lanes1 x, Lanes1 k) { return {std::ldexp(x.v, static_cast<int>(k.v))}; }
    friend Lanes1 nearest_integer(Lanes1 x) { return {std::nearbyint(x.v)}; }
    friend Lanes1 max(Lanes1 a, Lanes1 b) { return {a.v > b.v ? a.v : b.v}; }
    friend Lanes1 min(Lanes1 a, Lanes1 b) { return {a.v < b.v ? a.v : b.v}; }
    friend Lanes1 abs(Lanes1 a) { return {std::fabs(a.v)}; }
    friend Lanes1 max_magnitude(Lanes1 a, Lanes1 b) { return {std::fmax(std::fabs(a.v), std::fabs(b.v))}; }
    friend Mask operator<(Lanes1 a, Lanes1 b) { return a.v < b.v; }
    friend Mask operator<=(Lanes1 a, Lanes1 b) { return a.v <= b.v; }
    static void store_flags(std::uint8_t *p, unsigned flags, unsigned where) {
        if (where & 1u) *p = static_cast<std::uint8_t>(flags & 1u);
    }
    static Mask both(Mask a, Mask b) { return a && b; }
    // The lanes of m where a > b.
    static Mask greater_where(Mask m, Lanes1 a, Lanes1 b) { return m && a.v > b.v; }
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
    friend Lanes8 sqrt(Lanes8 a) { return {_mm512_sqrt_pd(a.v)}; }
    friend Lanes8 operator/(Lanes8 a, Lanes8 b) { return {_mm512_div_pd(a.v, b.v)}; }
    friend Lanes8 mantissa_exponent(Lanes8 x, Lanes8 &e) {
        e = {_mm512_getexp_pd(x.v)};
        return {_mm512_getmant_pd(x.v, _MM_MANT_NORM_1_2, _MM_MANT_SIGN_zero)};
    }
    friend Lanes8 scale_by_power_of_two(Lanes8 x, Lanes8 k) { return {_mm512_scalef_pd(x.v, k.v)}; }
    friend Lanes8 nearest_integer(Lanes8 x) {
        return {_mm512_roundscale_pd(x.v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC)};
    }
    friend Lanes8 max(Lanes8 a, Lanes8 b) { return {_mm512_max_pd(a.v, b.v)}; }
    friend Lanes8 min(Lanes8 a, Lanes8 b) { return {_mm512_min_pd(a.v, b.v)}; }
    friend Lanes8 abs(Lanes8 a) { return {_mm512_abs_pd(a.v)}; }
    // The larger of |a| and |b| in one instruction (range, imm 0b1011: the larger magnitude, sign cleared).
    friend Lanes8 max_magnitude(Lanes8 a, Lanes8 b) { return {_mm512_range_pd(a.v, b.v, 0x0B)}; }
    friend Mask operator<(Lanes8 a, Lanes8 b) { return _mm512_cmp_pd_mask(a.v, b.v, _CMP_LT_OQ); }
    friend Mask operator<=(Lanes8 a, Lanes8 b) { return _mm512_cmp_pd_mask(a.v, b.v, _CMP_LE_OQ); }
    // Bytes 1 or 0 (the lanes of `flags`) at the lanes of `where`.
    static void store_flags(std::uint8_t *p, unsigned flags, unsigned where) {
        _mm_mask_storeu_epi8(p, static_cast<__mmask16>(where & 0xFFu),
                             _mm_maskz_set1_epi8(static_cast<__mmask16>(flags & 0xFFu), 1));
    }
    static Mask both(Mask a, Mask b) { return static_cast<Mask>(a & b); }
    static Mask greater_where(Mask m, Lanes8 a, Lanes8 b) { return _mm512_mask_cmp_pd_mask(m, a.v, b.v, _CMP_GT_OQ); }
    static Mask either(Mask a, Mask b) { return static_cast<Mask>(a | b); }
    static Mask but_not(Mask a, Mask b) { return static_cast<Mask>(a & ~b); }
    static unsigned bits(Mask m) { return m; }
    static Mask from_bits(unsigned b) { return static_cast<Mask>(b); }
    static double hmax(Lanes8 a) {
        alignas(64) double x[8];
        _mm512_store_pd(x, a.v);
        return largest_of(x);
    }
};
#endif

#if defined(__AVX2__) && defined(__FMA__)
// Four doubles in an AVX2 register, for CPUs without AVX-512. AVX2 has no
// mask registers: a mask is a vector of all-ones or all-zero lanes. It has
// no reciprocal square root estimate in double: rsqrt divides by sqrt, as
// Lanes1 does (one rounding more than Lanes1's `1 / sqrt`, none fewer).
struct Lanes4 {
    static constexpr int width = 4;
    struct Mask {
        __m256d m;
    };
    __m256d v;

    static Lanes4 broadcast(double x) { return {_mm256_set1_pd(x)}; }
    static Lanes4 load(const double *p) { return {_mm256_loadu_pd(p)}; }
    static Lanes4 load(const float *p) { return {_mm256_cvtps_pd(_mm_loadu_ps(p))}; }
    void store(double *p) const { _mm256_storeu_pd(p, v); }
    void store_where(double *p, Mask m) const { _mm256_maskstore_pd(p, _mm256_castpd_si256(m.m), v); }
    void store_where(float *p, Mask m) const {
        // The lanes' masks, 64 bits each, narrowed to 32 as the floats are.
        const __m256i low_halves = _mm256_permutevar8x32_epi32(_mm256_castpd_si256(m.m), _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0));
        _mm_maskstore_ps(p, _mm256_castsi256_si128(low_halves), _mm256_cvtpd_ps(v));
    }
    static Mask first_lanes(int n) {
        return {_mm256_cmp_pd(_mm256_setr_pd(0.0, 1.0, 2.0, 3.0), _mm256_set1_pd(static_cast<double>(n)), _CMP_LT_OQ)};
    }
    static Mask kind_is(const std::uint8_t *p, std::uint8_t k) {
        std::int32_t four;
        std::memcpy(&four, p, sizeof four);
        const __m256i kinds = _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(four));
        return {_mm256_castsi256_pd(_mm256_cmpeq_epi64(kinds, _mm256_set1_epi64x(k)))};
    }

    friend Lanes4 operator+(Lanes4 a, Lanes4 b) { return {_mm256_add_pd(a.v, b.v)}; }
    friend Lanes4 operator-(Lanes4 a, Lanes4 b) { return {_mm256_sub_pd(a.v, b.v)}; }
    friend Lanes4 operator*(Lanes4 a, Lanes4 b) { return {_mm256_mul_pd(a.v, b.v)}; }
    friend Mask operator>(Lanes4 a, Lanes4 b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_GT_OQ)}; }
    friend Mask operator!=(Lanes4 a, Lanes4 b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_NEQ_UQ)}; }
    friend Lanes4 select(Mask m, Lanes4 a, Lanes4 b) { return {_mm256_blendv_pd(b.v, a.v, m.m)}; }
    friend Lanes4 fma(Lanes4 a, Lanes4 b, Lanes4 c) { return {_mm256_fmadd_pd(a.v, b.v, c.v)}; }
    friend Lanes4 fnma(Lanes4 a, Lanes4 b, Lanes4 c) { return {_mm256_fnmadd_pd(a.v, b.v, c.v)}; }
    friend Lanes4 mul_where(Mask m, Lanes4 a, Lanes4 b) { return {_mm256_and_pd(m.m, _mm256_mul_pd(a.v, b.v))}; }
    friend Lanes4 max_where(Mask m, Lanes4 a, Lanes4 b) {
        return {_mm256_blendv_pd(a.v, _mm256_max_pd(a.v, b.v), m.m)};
    }
    // [prev3, cur0, cur1, cur2] and [cur1, cur2, cur3, next0].
    static Lanes4 shift_west(Lanes4 prev, Lanes4 cur) {
        return {_mm256_shuffle_pd(_mm256_permute2f128_pd(prev.v, cur.v, 0x21), cur.v, 0x5)};
    }
    static Lanes4 shift_east(Lanes4 cur, Lanes4 next) {
        return {_mm256_shuffle_pd(cur.v, _mm256_permute2f128_pd(cur.v, next.v, 0x21), 0x5)};
    }
    friend Lanes4 rsqrt(Lanes4 a) { return {_mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(a.v))}; }
    friend Lanes4 rsqrt_fast(Lanes4 a) { return rsqrt(a); }
    friend Lanes4 sqrt(Lanes4 a) { return {_mm256_sqrt_pd(a.v)}; }
    friend Lanes4 operator/(Lanes4 a, Lanes4 b) { return {_mm256_div_pd(a.v, b.v)}; }
    // No getexp and getmant: the bits. The biased exponent (below 2^11) as
    // the low bits of 2^52 is 2^52 plus itself, exactly.
    friend Lanes4 mantissa_exponent(Lanes4 x, Lanes4 &e) {
        const __m256i bits = _mm256_castpd_si256(x.v);
        const __m256d two_52 = _mm256_set1_pd(4503599627370496.0);
        const __m256i biased = _mm256_or_si256(_mm256_srli_epi64(bits, 52), _mm256_castpd_si256(two_52));
        e = {_mm256_sub_pd(_mm256_castsi256_pd(biased), _mm256_set1_pd(4503599627370496.0 + 1023.0))};
        const __m256i mantissa = _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi64x(0x000FFFFFFFFFFFFF)),
                                                 _mm256_set1_epi64x(0x3FF0000000000000));
        return {_mm256_castsi256_pd(mantissa)};
    }
    // 2^k from its exponent bits, k + 1023 (within [1, 2046]) as the low bits of 2^52.
    friend Lanes4 scale_by_power_of_two(Lanes4 x, Lanes4 k) {
        const __m256d biased = _mm256_add_pd(k.v, _mm256_set1_pd(4503599627370496.0 + 1023.0));
        return {_mm256_mul_pd(x.v, _mm256_castsi256_pd(_mm256_slli_epi64(_mm256_castpd_si256(biased), 52)))};
    }
    friend Lanes4 nearest_integer(Lanes4 x) { return {_mm256_round_pd(x.v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC)}; }
    friend Lanes4 max(Lanes4 a, Lanes4 b) { return {_mm256_max_pd(a.v, b.v)}; }
    friend Lanes4 min(Lanes4 a, Lanes4 b) { return {_mm256_min_pd(a.v, b.v)}; }
    friend Lanes4 abs(Lanes4 a) { return {_mm256_andnot_pd(_mm256_set1_pd(-0.0), a.v)}; }
    friend Lanes4 max_magnitude(Lanes4 a, Lanes4 b) { return max(abs(a), abs(b)); }
    friend Mask operator<(Lanes4 a, Lanes4 b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_LT_OQ)}; }
    friend Mask operator<=(Lanes4 a, Lanes4 b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_LE_OQ)}; }
    static void store_flags(std::uint8_t *p, unsigned flags, unsigned where) {
        for (int k = 0; k < width; ++k)
            if ((where >> k) & 1u) p[k] = static_cast<std::uint8_t>((flags >> k) & 1u);
    }
    static Mask both(Mask a, Mask b) { return {_mm256_and_pd(a.m, b.m)}; }
    static Mask greater_where(Mask m, Lanes4 a, Lanes4 b) { return both(m, a > b); }
    static Mask either(Mask a, Mask b) { return {_mm256_or_pd(a.m, b.m)}; }
    static Mask but_not(Mask a, Mask b) { return {_mm256_andnot_pd(b.m, a.m)}; }
    static unsigned bits(Mask m) { return static_cast<unsigned>(_mm256_movemask_pd(m.m)); }
    static Mask from_bits(unsigned b) {
        const __m256i lane_bits = _mm256_setr_epi64x(1, 2, 4, 8);
        const __m256i set = _mm256_and_si256(_mm256_set1_epi64x(static_cast<long long>(b)), lane_bits);
        return {_mm256_castsi256_pd(_mm256_cmpeq_epi64(set, lane_bits))};
    }
    static double hmax(Lanes4 a) {
        alignas(32) double x[4];
        _mm256_store_pd(x, a.v);
        return largest_of(x);
    }
};
#endif

// Horner's rule: c[0] + x (c[1] + x (c[2] + ...)).
template <class V, int N>
inline V polynomial(V x, const double (&c)[N]) {
    V sum = V::broadcast(c[N - 1]);
    for (int i = N - 2; i >= 0; --i) sum = fma(sum, x, V::broadcast(c[i]));
    return sum;
}

// x^y for normal x > 0 and x^y within the normal range, lane by lane (there
// is no pow in lanes): exp(y ln x). ln x = e ln 2 + ln m with x = m 2^e, m in
// [sqrt(1/2), sqrt(2)), and ln m = 2 atanh(s), s = (m - 1) / (m + 1), by its
// series to s^23 (|s| < 0.172: what is cut is below 1e-17); exp(t) = 2^k
// exp(r), r = t - k ln 2 within ln(2) / 2, by its Taylor series to r^13
// (what is cut is below 5e-18); ln 2 in two parts whose first times k or e
// is exact. Against std::pow, for y in [0, 1]: within 7e-16 relative for x
// in [1e-3, 10], 2e-15 in [1e-8, 1e8], 6e-14 near 1e-300 or 1e300 (the
// rounding of y ln x, which exp turns into a relative error, grows with it).
template <class V>
inline V power(V x, V y) {
    constexpr double kLn2High = 6.93147180369123816490e-01, kLn2Low = 1.90821492927058770002e-10;
    static constexpr double kAtanh[] = {2.0,        2.0 / 3.0,  2.0 / 5.0,  2.0 / 7.0,  2.0 / 9.0,  2.0 / 11.0,
                                        2.0 / 13.0, 2.0 / 15.0, 2.0 / 17.0, 2.0 / 19.0, 2.0 / 21.0, 2.0 / 23.0};
    static constexpr double kExp[] = {1.0,
                                      1.0,
                                      1.0 / 2.0,
                                      1.0 / 6.0,
                                      1.0 / 24.0,
                                      1.0 / 120.0,
                                      1.0 / 720.0,
                                      1.0 / 5040.0,
                                      1.0 / 40320.0,
                                      1.0 / 362880.0,
                                      1.0 / 3628800.0,
                                      1.0 / 39916800.0,
                                      1.0 / 479001600.0,
                                      1.0 / 6227020800.0};
    const V one = V::broadcast(1.0);
    V e;
    V m = mantissa_exponent(x, e);
    const auto upper = V::broadcast(1.4142135623730951) < m;  // m > sqrt(2): m / 2, e + 1
    m = select(upper, m * V::broadcast(0.5), m);
    e = select(upper, e + one, e);
    const V s = (m - one) / (m + one);
    const V ln_m = s * polynomial(s * s, kAtanh);
    const V t = y * fma(e, V::broadcast(kLn2High), fma(e, V::broadcast(kLn2Low), ln_m));
    const V k = nearest_integer(t * V::broadcast(1.0 / kLn2High));
    const V r = fnma(k, V::broadcast(kLn2Low), fnma(k, V::broadcast(kLn2High), t));
    return scale_by_power_of_two(polynomial(r, kExp), k);
}

}  // namespace dpsm::simd
