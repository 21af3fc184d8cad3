/* environment_model — shikki_scene_set_environment_model / _get_environment_model: the default is
 * SHIKKI_ENV_MODEL_PAPER; SHIKKI_ENV_MODEL_BRDF renders a smooth sphere lit by the studio
 * environment alone (no lights, 32 × 32, 1 sample) differently from PAPER, and switching back
 * gives PAPER's bytes again; a scene TOML's `[render] environment_model = "brdf"` reaches the
 * handle and renders exactly like the call-built BRDF scene; an unknown model number is
 * INVALID_ARGUMENT naming the valid values and leaves the scene as it was. Run by
 * ffi/tests/c_api.rs. Prints one line per check; exit status = number of failed checks.
 */
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { SIDE = 32, LEN = SIDE * SIDE * 4 };

/* The scene the call-built one is, as scene TOML (the scene-file defaults fill in the rest). */
static const char *const brdf_toml = "light = []\n"
                                     "[[object]]\n"
                                     "mesh = \"builtin:sphere\"\n"
                                     "material = { preset = \"smooth-red\" }\n"
                                     "[environment]\n"
                                     "source = \"builtin:studio\"\n"
                                     "[output]\n"
                                     "size = [32, 32]\n"
                                     "samples = 1\n"
                                     "[render]\n"
                                     "environment_model = \"brdf\"\n";

/* The model the scene holds now, or UINT32_MAX when the getter fails (a failed check). */
static uint32_t model_of(ShikkiScene scene) {
    uint32_t model = UINT32_MAX;
    EXPECT(shikki_scene_get_environment_model(scene, &model), SHIKKI_STATUS_OK);
    return model;
}

/* The largest difference of any channel between two RGBA32F images of LEN floats, and in how
 * many pixels they differ at all. */
static double max_difference(const float *a, const float *b, int *pixels_differing) {
    double largest = 0.0;
    *pixels_differing = 0;
    for (size_t p = 0; p < LEN; p += 4) {
        int differs = 0;
        for (size_t i = p; i < p + 4; i++) {
            double d = fabs((double)a[i] - (double)b[i]);
            if (d > largest) largest = d;
            differs |= d > 0.0;
        }
        *pixels_differing += differs;
    }
    return largest;
}

int main(void) {
    ShikkiRenderer renderer = {0};
    ShikkiMesh sphere = {0};
    ShikkiMaterial red = {0};
    ShikkiEnvironment studio = {0};
    ShikkiScene scene = {0}, from_toml = {0}, bad_toml = {0};
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    float *paper = calloc(LEN, sizeof(float));
    float *brdf = calloc(LEN, sizeof(float));
    float *paper_again = calloc(LEN, sizeof(float));
    float *toml_brdf = calloc(LEN, sizeof(float));
    if (!paper || !brdf || !paper_again || !toml_brdf) {
        printf("FAIL out of memory\n");
        return 1;
    }

    /* The scene: a smooth red sphere lit by the studio map alone. */
    EXPECT(shikki_mesh_create_builtin("sphere", &sphere), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_create_preset("smooth-red", &red), SHIKKI_STATUS_OK);
    EXPECT(shikki_environment_load("builtin:studio", &studio), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_create(&scene), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_add_object(scene, sphere, red, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_environment(scene, studio, 1.0, 0.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_output(scene, SIDE, SIDE, 1), SHIKKI_STATUS_OK);
    EXPECT(shikki_mesh_destroy(sphere), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(red), SHIKKI_STATUS_OK);
    EXPECT(shikki_environment_destroy(studio), SHIKKI_STATUS_OK);

    /* The default, the getter's own errors, the setter's errors. */
    EXPECT_TRUE(model_of(scene) == SHIKKI_ENV_MODEL_PAPER);
    EXPECT_MESSAGE(shikki_scene_get_environment_model(scene, NULL), SHIKKI_STATUS_NULL_ARGUMENT,
                   "`model`");
    uint32_t untouched = 77;
    EXPECT_MESSAGE(shikki_scene_get_environment_model((ShikkiScene){0}, &untouched),
                   SHIKKI_STATUS_INVALID_HANDLE, "ShikkiScene");
    EXPECT_TRUE(untouched == 77);
    EXPECT_MESSAGE(shikki_scene_set_environment_model((ShikkiScene){0}, SHIKKI_ENV_MODEL_BRDF),
                   SHIKKI_STATUS_INVALID_HANDLE, "ShikkiScene");
    EXPECT(shikki_scene_set_environment_model(scene, SHIKKI_ENV_MODEL_BRDF), SHIKKI_STATUS_OK);
    EXPECT_TRUE(model_of(scene) == SHIKKI_ENV_MODEL_BRDF);
    EXPECT_MESSAGE(shikki_scene_set_environment_model(scene, 2), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "SHIKKI_ENV_MODEL_PAPER (0)");
    EXPECT_MESSAGE(shikki_scene_set_environment_model(scene, UINT32_MAX),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "_BRDF (1)");
    EXPECT_TRUE(model_of(scene) == SHIKKI_ENV_MODEL_BRDF); /* unchanged by the failures */
    EXPECT(shikki_scene_set_environment_model(scene, SHIKKI_ENV_MODEL_PAPER), SHIKKI_STATUS_OK);
    EXPECT_TRUE(model_of(scene) == SHIKKI_ENV_MODEL_PAPER);

    /* Scene TOML: `[render] environment_model` reaches the handle; a bad name is a parse error
     * naming the valid ones. */
    EXPECT(shikki_scene_create_toml(brdf_toml, NULL, &from_toml), SHIKKI_STATUS_OK);
    EXPECT_TRUE(model_of(from_toml) == SHIKKI_ENV_MODEL_BRDF);
    EXPECT_MESSAGE(shikki_scene_create_toml("[render]\nenvironment_model = \"phong\"\n", NULL,
                                            &bad_toml),
                   SHIKKI_STATUS_PARSE_ERROR, "`paper` or `brdf`");
    EXPECT_TRUE(bad_toml.id == 0);

    /* Rendering: PAPER, BRDF, PAPER again, and the TOML scene's BRDF. */
    EXPECT(shikki_renderer_create(&options, &renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, paper, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_environment_model(scene, SHIKKI_ENV_MODEL_BRDF), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, brdf, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_environment_model(scene, SHIKKI_ENV_MODEL_PAPER), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, paper_again, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, from_toml, toml_brdf, LEN), SHIKKI_STATUS_OK);

    /* The sphere covers the centre pixel in both renders, with finite, positive radiance. */
    const size_t centre = 4 * ((SIDE / 2) * SIDE + SIDE / 2);
    EXPECT_TRUE(paper[centre + 3] == 1.0f && brdf[centre + 3] == 1.0f);
    EXPECT_TRUE(isfinite(paper[centre]) && paper[centre] > 0.0f);
    EXPECT_TRUE(isfinite(brdf[centre]) && brdf[centre] > 0.0f);
    int pixels_differing = 0;
    const double difference = max_difference(paper, brdf, &pixels_differing);
    printf("info PAPER/BRDF: largest difference %g, %d of %d pixels differ (centre red %g vs %g)\n",
           difference, pixels_differing, SIDE * SIDE, paper[centre], brdf[centre]);
    EXPECT_TRUE(difference > 1e-4); /* BRDF is another model: not the same pixels */
    EXPECT_TRUE(memcmp(paper, paper_again, LEN * sizeof(float)) == 0);
    EXPECT_TRUE(memcmp(brdf, toml_brdf, LEN * sizeof(float)) == 0);

    size_t messages = 99;
    EXPECT(shikki_renderer_validation_message_count(renderer, &messages), SHIKKI_STATUS_OK);
    EXPECT_TRUE(messages == 0);

    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(from_toml), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shikki_live_handle_count() == 0);
    free(paper);
    free(brdf);
    free(paper_again);
    free(toml_brdf);
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
