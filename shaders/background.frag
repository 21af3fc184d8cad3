#version 450
// The sharp environment (layer 0) seen along each pixel's primary ray (SPEC §1's camera rays).

#include "frame.glsl"

layout(location = 0) out vec4 out_radiance;

void main() {
    float tan_half = frame.camera_params.x;
    float aspect = frame.camera_params.y;
    vec2 size = frame.camera_params.zw;
    // gl_FragCoord is the pixel centre (i + ½, j + ½) in the target, row 0 at the top; the
    // target holds image rows from strip_offset.y on.
    float x = (2.0 * gl_FragCoord.x / size.x - 1.0) * tan_half * aspect;
    float y = (1.0 - 2.0 * (gl_FragCoord.y + frame.strip_offset.y) / size.y) * tan_half;
    vec3 dir = normalize(x * frame.camera_right.xyz + y * frame.camera_up.xyz - frame.camera_back.xyz);
    out_radiance = vec4(sharp_radiance(dir), 1.0);
}
