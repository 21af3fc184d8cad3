// Accurate inverse trigonometry (quirk `imprecise_inverse_trig`: GLSL's acos/atan have no useful
// precision bound in Vulkan): these are exact to about 1e-7 rad everywhere.
#ifndef MATH_GLSL
#define MATH_GLSL

const float PI = 3.14159265358979323846;
const float HALF_PI = 1.57079632679489661923;

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
