#version 450
// Step 1's second dispatch with shaderFloat64: finishes the texels equirect_to_cube_f64.comp listed
// (sub-samples near a pixel edge, in double precision; see the body).
#define PRECISE_COORDINATES
#define NEAR_PASS
#include "equirect_to_cube_body.glsl"
