#version 450
// A constant colour, drawn forward: the same geometry as the lacquer draw with no shading cost, so
// `shikki bench` can measure the rasteriser's floor (vertex work, binning, depth test, MSAA
// resolve).

// Declared so the interface matches mesh.vert (validation warns about unconsumed outputs).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec4 out_radiance;

void main() {
    out_radiance = vec4(0.5, 0.25, 0.125, 1.0);
}
