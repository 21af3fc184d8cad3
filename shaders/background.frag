#version 450
// The sharp environment (layer 0) seen along each pixel's primary ray (SPEC §1's camera rays):
// the background of forward draws (the benchmark's trivial shader); the lacquer draw computes it in
// coverage.frag.

#include "frame.glsl"

layout(location = 0) out vec4 out_radiance;

void main() {
    // gl_FragCoord is the pixel centre (i + ½, j + ½) in the target, row 0 at the top; the
    // target holds image rows from strip_offset.y on.
    vec2 pixel = vec2(gl_FragCoord.x, gl_FragCoord.y + frame.strip_offset.y);
    out_radiance = vec4(sharp_radiance(camera_ray(pixel)), 1.0);
}
