#version 450
// Double-precision source coordinates (needs shaderFloat64; see the body).
#define PRECISE_COORDINATES
#include "equirect_to_cube_body.glsl"
