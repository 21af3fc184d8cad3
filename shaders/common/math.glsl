// Accurate inverse trigonometry (quirk `imprecise_inverse_trig`: GLSL's acos/atan have no useful
// precision bound in Vulkan): these are exact to about 1e-7 rad everywhere. And whole numbers to
// int without int()'s conversion lane by lane.
#ifndef MATH_GLSL
#define MATH_GLSL

const float PI = 3.14159265358979323846;
const float HALF_PI = 1.57079632679489661923;

// int(x) for a whole number x in [0, 2^23), without int()'s lane-by-lane conversion (quirk
// `float_to_int_is_per_lane`): 2^23 + x holds x in its mantissa's low bits, so one vector add and
// one subtract give the same integer. Below 0 (and NaN) 0, from 2^23 up 2^23 − 1: callers clamp to
// a smaller range anyway.
int whole_to_int(float x) {
    return floatBitsToInt((x >= 0.0 ? min(x, 8388607.0) : 0.0) + 8388608.0) - 0x4B000000;
}

ivec2 whole_to_int(vec2 x) {
    return ivec2(whole_to_int(x.x), whole_to_int(x.y));
}

// int(x) for a whole number x in [−2^22, 2^22), the same way: 1.5·2^23 + x holds 2^22 + x in its
// mantissa's low bits. Beyond the range the nearest end; NaN 0.
int signed_whole_to_int(float x) {
    float held = x >= -4194304.0 ? min(x, 4194303.0) : (x < 0.0 ? -4194304.0 : 0.0);
    return floatBitsToInt(held + 12582912.0) - 0x4B400000;
}

// acos on [0, 1] (Abramowitz & Stegun 4.4.46): sqrt(1 − x)·Σ a_i x^i, |error| ≤ 2e-8.
float acos_unit(float x) {
    x = clamp(x, 0.0, 1.0);
    float p = -0.0012624911;
    p = p * x + 0.0066700901;
    p = p * x - 0.0170881256;
    p = p * x + 0.0308918810;
    p = p * x - 0.0501743046;
    p = p * x + 0.0889789874;
    p = p * x - 0.2145988016;
    p = p * x + 1.5707963050;
    return sqrt(1.0 - x) * p;
}

// atan2(y, x) in (−π, π], ~1e-7 rad: the angle of (|x|, |y|) from whichever of asin/acos is
// well-conditioned there, then the quadrant.
float atan2_accurate(float y, float x) {
    float ax = abs(x);
    float ay = abs(y);
    float r = sqrt(ax * ax + ay * ay);
    if (r == 0.0) {
        return 0.0;
    }
    float a = ay <= ax ? HALF_PI - acos_unit(ay / r) : acos_unit(ax / r);
    if (x < 0.0) {
        a = PI - a;
    }
    return y < 0.0 ? -a : a;
}

// The variance of the mean of n samples from their sums (Σx, Σx²): the unbiased sample
// variance over n; with one sample, that sample's square (its spread is unknown, and a lone
// estimate is all noise). Twin: oracle::light_between::sample_variance_of_mean.
float sample_variance_of_mean(vec2 moments, float n) {
    if (n < 2.0) {
        return moments.x * moments.x;
    }
    return max(moments.y - moments.x * moments.x / n, 0.0) / (n * (n - 1.0));
}

#endif
