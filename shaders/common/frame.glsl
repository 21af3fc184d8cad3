// Per-draw uniforms shared by mesh.vert and lacquer.frag (std140). The host side is
// src/raster/uniforms.rs: change both together.
#ifndef FRAME_GLSL
#define FRAME_GLSL

const int MAX_LIGHTS = 16;

layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view_projection;
    vec4 eye;              // xyz: camera position
    vec4 material;         // m, a, b, g(r)
    vec4 albedo_count;     // k_d.rgb, fresnel knot count
    vec4 material_lo;      // (a_lo, b_lo, 0, 0): what rounding a and b to f32 lost
    ivec4 light_count;     // x: number of lights
    vec4 light_vector[MAX_LIGHTS]; // w = 0: directional, xyz towards the light; w = 1: point, xyz position
    vec4 light_color[MAX_LIGHTS];  // rgb: irradiance E (directional) or intensity I (point)
} frame;

#endif
