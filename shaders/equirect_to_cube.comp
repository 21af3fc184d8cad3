#version 450
// fp32 variant, for devices without shaderFloat64 (see the body).
#include "equirect_to_cube_body.glsl"
