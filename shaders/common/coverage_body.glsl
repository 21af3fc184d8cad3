// The first draw of the lacquer shading pass (coverage.frag, coverage_ms.frag), a full-screen
// triangle (scissored to the meshes' screen bounds when the background is a colour, which is then
// the clear colour and this draw writes no colour): the single-sampled depth target records
// whether any G-buffer sample of the pixel is covered (depth 0) or none is (depth 1, the clear
// value), and with the environment as background every pixel gets it.
// shade.frag then draws with an early depth test that passes only where depth is 0: llvmpipe skips
// a block of pixels whose lanes all fail an early depth test, but runs both sides of a branch or a
// `discard` under a lane mask (quirk `loop_body_runs_when_no_lane_enters`), so this is how the
// shading of uncovered pixels is skipped.
//
// The includer defines MULTISAMPLED or not.

#include "frame.glsl"

#include "gbuffer_samples.glsl"

layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    bool covered = false;
    for (int s = 0; s < SAMPLE_COUNT; ++s) {
        covered = covered || FETCH(gbuffer_position, texel, s).w != 0.0;
    }
    // The pixel centre in whole-image coordinates, as in background.frag.
    vec2 pixel = vec2(gl_FragCoord.x, gl_FragCoord.y + frame.strip_offset.y);
    out_radiance = background_radiance(pixel);
    gl_FragDepth = covered ? 0.0 : 1.0;
}
