/* error_paths — every error path of the C API returns the documented status and a non-empty
 * message, and a scene built entirely with calls (mesh and environment from caller arrays,
 * material setters, transform, lights, camera) renders. Run by ffi/tests/c_api.rs, also under
 * valgrind. Prints one line per check; exit status = number of failed checks.
 */
#include <shikki.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;
static int checks = 0;

/* `status` must equal `want`; on an error the message must be non-empty, on success empty. */
static void expect(const char *what, ShikkiStatus status, ShikkiStatus want) {
    const char *message = shikki_last_error();
    int ok = status == want && message != NULL &&
             (want == SHIKKI_STATUS_OK ? message[0] == '\0' : message[0] != '\0');
    checks++;
    if (!ok) failures++;
    printf("%s %s: status %d (want %d): %s\n", ok ? "ok  " : "FAIL", what, (int)status,
           (int)want, message ? message : "(NULL message)");
}

#define EXPECT(call, want) expect(#call, (call), (want))

/* An octahedron: 6 vertices, 8 outward-facing (counter-clockwise) triangles. */
static const float octa_positions[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
static const uint32_t octa_indices[] = {0, 2, 4, 4, 2, 1, 1, 2, 5, 5, 2, 0,
                                        4, 3, 0, 1, 3, 4, 5, 3, 1, 0, 3, 5};

int main(void) {
    ShikkiRenderer renderer = {0};
    ShikkiMaterial material = {0}, destroyed = {0}, from_toml = {0};
    ShikkiMesh mesh = {0};
    ShikkiEnvironment environment = {0};
    ShikkiScene scene = {0}, bad_scene = {0};
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };

    /* shikki_version and shikki_last_error never return NULL. */
    checks++;
    if (shikki_version() == NULL || shikki_version()[0] == '\0') failures++;

    /* NULL arguments. */
    EXPECT(shikki_material_create_preset(NULL, &material), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_material_create_preset("smooth", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_material_create_toml(NULL, NULL, &from_toml), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_create(NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_renderer_create(&options, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_create(NULL, NULL, 3, octa_indices, 3, &mesh), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_environment_create_rgb(2, 1, NULL, &environment), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_environment_load(NULL, &environment), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_image_write(NULL, 4, 1, 1, 0.0f, SHIKKI_TONE_CURVE_ACES, "x.png"),
           SHIKKI_STATUS_NULL_ARGUMENT);

    /* Bad preset, bad values, bad TOML. */
    EXPECT(shikki_material_create_preset("glossy-blue", &material), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_create_toml("preset = \"smooth\"\nm = [", NULL, &from_toml),
           SHIKKI_STATUS_PARSE_ERROR);
    EXPECT(shikki_scene_create_toml("[camera\neye = 1", NULL, &bad_scene), SHIKKI_STATUS_PARSE_ERROR);
    EXPECT(shikki_mesh_create_builtin("teapot", &mesh), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_environment_load("/nonexistent/sky.hdr", &environment), SHIKKI_STATUS_IO_ERROR);

    /* A material built with every setter. */
    EXPECT(shikki_material_create_preset("rough-red", &material), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beckmann_m(material, 1.5), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set_albedo(material, 0.5, 2.0, 0.0), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set(material, "shininess", "3"), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set_beckmann_m(material, 0.15), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_diffuse_a(material, 0.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_diffuse_b(material, 1.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_lacquer_law(material, 1.22, -0.224, 0.0199), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_lacquer_ratio(material, 9.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_validate(material), SHIKKI_STATUS_INVALID_ARGUMENT); /* r > r* */
    EXPECT(shikki_material_set_lacquer_ratio(material, 2.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_extrapolate_g(material, false), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_albedo(material, 0.4, 0.05, 0.03), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_ior_a(material, 1.52), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_ior_b(material, 0.004), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_fresnel_file(material, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beta_normal(material, 0.5), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beta_grazing(material, 0.05), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beta_power(material, 2.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_validate(material), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_create_toml("preset = \"smooth-black\"\nm = 0.08\n", NULL, &from_toml),
           SHIKKI_STATUS_OK);

    /* Destroyed, zero, forged and wrong-kind handles. */
    EXPECT(shikki_material_create_preset("smooth", &destroyed), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(destroyed), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beckmann_m(destroyed, 0.1), SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_material_destroy(destroyed), SHIKKI_STATUS_INVALID_HANDLE);
    ShikkiMaterial forged = {.id = 0x123456789abcULL};
    EXPECT(shikki_material_validate(forged), SHIKKI_STATUS_INVALID_HANDLE);
    ShikkiMaterial zero = {0};
    EXPECT(shikki_material_validate(zero), SHIKKI_STATUS_INVALID_HANDLE);
    ShikkiScene not_a_scene = {.id = material.id};
    EXPECT(shikki_scene_clear_lights(not_a_scene), SHIKKI_STATUS_INVALID_HANDLE);

    /* A scene built with calls: mesh and environment from caller arrays. */
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, &mesh), SHIKKI_STATUS_OK);
    uint32_t bad_indices[] = {0, 1, 7};
    ShikkiMesh bad_mesh = {0};
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, bad_indices, 3, &bad_mesh),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    enum { ENV_W = 16, ENV_H = 8 };
    float *sky = malloc(sizeof(float) * ENV_W * ENV_H * 3);
    for (int j = 0; j < ENV_H; j++)
        for (int i = 0; i < ENV_W; i++) {
            float up = 1.0f - (j + 0.5f) / ENV_H; /* brighter towards +Y */
            float *p = sky + 3 * (j * ENV_W + i);
            p[0] = 0.2f + up, p[1] = 0.25f + up, p[2] = 0.3f + 1.2f * up;
        }
    EXPECT(shikki_environment_create_rgb(ENV_W, ENV_H, sky, &environment), SHIKKI_STATUS_OK);
    sky[5] = -1.0f;
    ShikkiEnvironment bad_environment = {0};
    EXPECT(shikki_environment_create_rgb(ENV_W, ENV_H, sky, &bad_environment),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    free(sky);

    EXPECT(shikki_scene_create(&scene), SHIKKI_STATUS_OK);
    /* Column-major: scale 0.8, then translate by (0.1, -0.1, 0). */
    const double transform[16] = {0.8, 0, 0, 0, 0, 0.8, 0, 0, 0, 0, 0.8, 0, 0.1, -0.1, 0, 1};
    const double projective[16] = {1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    EXPECT(shikki_scene_add_object(scene, mesh, material, projective), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_add_object(scene, mesh, material, transform), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_add_object(scene, mesh, destroyed, NULL), SHIKKI_STATUS_INVALID_HANDLE);
    const double to_light[3] = {0.3, 1.0, 0.5}, irradiance[3] = {2.0, 2.0, 1.8};
    const double position[3] = {0.0, 2.0, 3.0}, intensity[3] = {5.0, 5.0, 5.0};
    const double zero3[3] = {0.0, 0.0, 0.0};
    EXPECT(shikki_scene_add_directional_light(scene, zero3, irradiance), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_add_directional_light(scene, to_light, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_add_directional_light(scene, to_light, irradiance), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_add_point_light(scene, position, intensity), SHIKKI_STATUS_OK);
    const double eye[3] = {0.0, 0.5, 3.5}, target[3] = {0.0, 0.0, 0.0};
    EXPECT(shikki_scene_set_camera(scene, eye, eye, NULL, 40.0), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_camera(scene, eye, target, NULL, 40.0), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_environment(scene, environment, 1.0, 30.0), SHIKKI_STATUS_OK);
    const float grey[3] = {0.1f, 0.1f, 0.1f};
    EXPECT(shikki_scene_set_background(scene, 7, grey), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_background(scene, SHIKKI_BACKGROUND_COLOR, grey), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_output(scene, 16, 16, 3), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_output(scene, 16, 12, 1), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_set_display(scene, 0.5f, 9), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_display(scene, 0.5f, SHIKKI_TONE_CURVE_REINHARD), SHIKKI_STATUS_OK);
    /* The scene holds its own references: the handles may go now. */
    EXPECT(shikki_mesh_destroy(mesh), SHIKKI_STATUS_OK);
    EXPECT(shikki_environment_destroy(environment), SHIKKI_STATUS_OK);

    /* Rendering: wrong buffer sizes, NULL buffers, a destroyed renderer. */
    EXPECT(shikki_renderer_create(&options, &renderer), SHIKKI_STATUS_OK);
    float hdr[16 * 12 * 4];
    uint8_t ldr[16 * 12 * 4];
    EXPECT(shikki_render_rgba32f(renderer, scene, hdr, 16 * 16 * 4), SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT(shikki_render_rgba8(renderer, scene, ldr, 16 * 12 * 3), SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT(shikki_render_rgba32f(renderer, scene, NULL, 16 * 12 * 4), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_render_to_file(renderer, scene, "out.bmp"), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_image_write(hdr, 7, 16, 12, 0.0f, SHIKKI_TONE_CURVE_ACES, "x.png"),
           SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT(shikki_render_rgba32f(renderer, scene, hdr, 16 * 12 * 4), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba8(renderer, scene, ldr, 16 * 12 * 4), SHIKKI_STATUS_OK);
    /* The object covers the centre pixel; the background colour fills the corner. */
    const float *centre = hdr + 4 * (6 * 16 + 8);
    checks++;
    if (!(centre[3] == 1.0f && centre[0] > 0.0f && isfinite(centre[0]) && hdr[0] == grey[0] &&
          ldr[4 * (6 * 16 + 8) + 3] == 255)) {
        failures++;
        printf("FAIL rendered pixels: centre (%g, %g, %g, %g), corner %g\n", centre[0], centre[1],
               centre[2], centre[3], hdr[0]);
    }
    size_t messages = 99;
    EXPECT(shikki_renderer_validation_message_count(renderer, &messages), SHIKKI_STATUS_OK);
    checks++;
    if (messages != 0) {
        failures++;
        printf("FAIL %zu validation message(s)\n", messages);
    }
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, hdr, 16 * 12 * 4), SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_INVALID_HANDLE);

    /* The message stays until the next call on this thread; a success clears it. */
    EXPECT(shikki_material_destroy(from_toml), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(material), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    checks++;
    if (shikki_live_handle_count() != 0) {
        failures++;
        printf("FAIL %zu handle(s) still alive\n", shikki_live_handle_count());
    }
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
