/* light_transport — shikki_scene_set_light_transport / _get_light_transport and
 * shikki_scene_set_light_paths / _get_light_paths (SPEC §6). Shadows and ray tracing are on
 * by default; a sphere resting on a board under a light from above renders a shadow on the board
 * with shadows on (on a device with ray queries), none with shadows off, and shadows off and ray
 * tracing off give the same bytes; the scene TOML's `[render] shadows = false` reaches the
 * handle. Run by ffi/tests/c_api.rs. Prints one line per check; exit status = number of failed
 * checks.
 */
#include "check.h"

#include <stdint.h>
#include <stdlib.h>

enum { SIDE = 48, LEN = SIDE * SIDE * 4 };

/* A sphere of radius 0.5 resting on the board, the light straight above, no environment. */
static const char *const scene_toml = "environment = \"none\"\n"
                                      "[camera]\n"
                                      "eye = [0.0, 3.0, 2.0]\n"
                                      "target = [0.0, 0.0, 0.0]\n"
                                      "[[light]]\n"
                                      "kind = \"dir\"\n"
                                      "to_light = [0.0, 1.0, 0.0]\n"
                                      "irradiance = [3.0, 3.0, 3.0]\n"
                                      "[[object]]\n"
                                      "mesh = \"builtin:sphere\"\n"
                                      "scale = 0.5\n"
                                      "translate = [0.0, 0.5, 0.0]\n"
                                      "material = { preset = \"smooth-red\" }\n"
                                      "[[object]]\n"
                                      "mesh = \"builtin:board\"\n"
                                      "material = { preset = \"rough-black\" }\n"
                                      "[output]\n"
                                      "size = [48, 48]\n"
                                      "samples = 1\n"
                                      "background = \"transparent\"\n";

/* Pixels black in `shadowed` but lit in `lit` (the board in the sphere's shadow: there is no
 * environment); `brighter` counts pixels `shadowed` has brighter than `lit` (must be none). */
static int newly_black(const float *shadowed, const float *lit, int *brighter) {
    int count = 0;
    *brighter = 0;
    for (size_t p = 0; p < LEN; p += 4) {
        count += shadowed[p + 3] == 1.0f && shadowed[p] == 0.0f && lit[p] > 0.0f;
        *brighter += shadowed[p] > lit[p];
    }
    return count;
}

static void warning_seen(void *user, const char *message) {
    (void)message;
    *(int *)user += 1;
}

int main(void) {
    ShikkiRenderer renderer = {0};
    ShikkiScene scene = {0}, off_toml = {0};
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    float *shadowed = calloc(LEN, sizeof(float));
    float *no_shadows = calloc(LEN, sizeof(float));
    float *no_rays = calloc(LEN, sizeof(float));
    if (!shadowed || !no_shadows || !no_rays) {
        printf("FAIL out of memory\n");
        return 1;
    }
    EXPECT(shikki_scene_create_toml(scene_toml, NULL, &scene), SHIKKI_STATUS_OK);
    int shadows = -1, rays = -1;
    EXPECT(shikki_scene_get_light_transport(scene, &shadows, &rays), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shadows == 1 && rays == 1);
    EXPECT(shikki_scene_get_light_transport(scene, NULL, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_light_transport((ShikkiScene){0}, &shadows, NULL),
           SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_scene_set_light_transport((ShikkiScene){0}, 1, 1), SHIKKI_STATUS_INVALID_HANDLE);
    uint32_t bounces = 99, count = 99, seed = 99;
    EXPECT(shikki_scene_get_light_paths(scene, &bounces, &count, &seed), SHIKKI_STATUS_OK);
    EXPECT_TRUE(bounces == 1 && count == 8 && seed == 0); /* the defaults */
    /* Shadows alone (no integral), so that shadows off traces nothing at all. */
    EXPECT(shikki_scene_set_light_paths(scene, 0, 1, 0), SHIKKI_STATUS_OK);

    int warnings = 0;
    EXPECT(shikki_renderer_create(&options, &renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_renderer_set_warning_callback(renderer, warning_seen, &warnings),
           SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, shadowed, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_light_transport(scene, 0, 1), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_light_transport(scene, &shadows, &rays), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shadows == 0 && rays == 1);
    EXPECT(shikki_render_rgba32f(renderer, scene, no_shadows, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_light_transport(scene, 1, 0), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, no_rays, LEN), SHIKKI_STATUS_OK);

    /* With shadows the board under the sphere is black and nothing is brighter (a device
     * without ray queries draws no shadow and says so once, by the callback). */
    const char *ray_env = getenv("SHIKKI_RAY_QUERY");
    int traced = ray_env == NULL || strcmp(ray_env, "0") != 0;
    int brighter = 0;
    int dark = newly_black(shadowed, no_shadows, &brighter);
    printf("info %d pixels in shadow, %d brighter with shadows; %d warning(s)\n", dark, brighter,
           warnings);
    EXPECT_TRUE(brighter == 0);
    EXPECT_TRUE(traced ? dark > 20 && warnings == 0 : dark == 0 && warnings == 1);
    EXPECT_TRUE(memcmp(no_shadows, no_rays, LEN * sizeof(float)) == 0);

    EXPECT(shikki_scene_create_toml("[render]\nshadows = false\nbounces = 2\nrays = 5\nseed = 9\n",
                                    NULL, &off_toml),
           SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_light_transport(off_toml, &shadows, &rays), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shadows == 0 && rays == 1);

    /* Bounces, rays and seed: the TOML's reach the handle; the defaults; ranges refused. */
    EXPECT(shikki_scene_get_light_paths(off_toml, &bounces, &count, &seed), SHIKKI_STATUS_OK);
    EXPECT_TRUE(bounces == 2 && count == 5 && seed == 9);
    EXPECT(shikki_scene_set_light_paths(scene, 5, 16, 0), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_light_paths(scene, 1, 0, 0), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_light_paths(scene, 1, 4097, 0), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_get_light_paths(scene, &bounces, &count, NULL), SHIKKI_STATUS_OK);
    EXPECT_TRUE(bounces == 0 && count == 1); /* unchanged by the refusals */
    EXPECT(shikki_scene_set_light_paths(scene, 2, 8, 3), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_light_paths(scene, &bounces, &count, &seed), SHIKKI_STATUS_OK);
    EXPECT_TRUE(bounces == 2 && count == 8 && seed == 3);

    /* The denoise switch: on by default, off by the setter or the TOML, NULL refused. */
    int denoise = -1;
    EXPECT(shikki_scene_get_denoise(scene, &denoise), SHIKKI_STATUS_OK);
    EXPECT_TRUE(denoise == 1);
    EXPECT(shikki_scene_set_denoise(scene, 0), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_denoise(scene, &denoise), SHIKKI_STATUS_OK);
    EXPECT_TRUE(denoise == 0);
    EXPECT(shikki_scene_get_denoise(scene, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_set_denoise((ShikkiScene){0}, 1), SHIKKI_STATUS_INVALID_HANDLE);
    ShikkiScene raw_toml = {0};
    EXPECT(shikki_scene_create_toml("[render]\ndenoise = false\n", NULL, &raw_toml),
           SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_denoise(raw_toml, &denoise), SHIKKI_STATUS_OK);
    EXPECT_TRUE(denoise == 0);
    EXPECT(shikki_scene_destroy(raw_toml), SHIKKI_STATUS_OK);

    size_t messages = 99;
    EXPECT(shikki_renderer_validation_message_count(renderer, &messages), SHIKKI_STATUS_OK);
    EXPECT_TRUE(messages == 0);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(off_toml), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shikki_live_handle_count() == 0);
    free(shadowed);
    free(no_shadows);
    free(no_rays);
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
