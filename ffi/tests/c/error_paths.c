/* error_paths — every error path of the C API returns the documented status and a non-empty
 * message, and a scene built entirely with calls (mesh and environment from caller arrays,
 * material setters, transform, lights, camera) renders. Hostile callers too: every handle kind
 * used after destroy, destroyed twice, stale after its slot is reused, forged, or passed as
 * another kind; NULL out-pointers; invalid UTF-8; sizes far beyond the limits. Run by
 * ffi/tests/c_api.rs, also under valgrind and ASan+UBSan. Prints one line per check; exit
 * status = number of failed checks.
 */
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* An octahedron: 6 vertices, 8 outward-facing (counter-clockwise) triangles. */
static const float octa_positions[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
static const uint32_t octa_indices[] = {0, 2, 4, 4, 2, 1, 1, 2, 5, 5, 2, 0,
                                        4, 3, 0, 1, 3, 4, 5, 3, 1, 0, 3, 5};

/* ---- Hostile handles --------------------------------------------------------------------
 * Handles are {uint64_t id} structs: slot index + 1 in the low 32 bits, the slot's generation in
 * the high 32 (docs/c-api.md). Every kind is tried where every other kind is expected. */

enum Kind { RENDERER, ENVIRONMENT, MESH, MATERIAL, SCENE, KINDS };
static const char *const kind_names[KINDS] = {"ShikkiRenderer", "ShikkiEnvironment", "ShikkiMesh",
                                              "ShikkiMaterial", "ShikkiScene"};

/* A live scene that environment handles are tried on. */
static ShikkiScene probe_scene = {0};

/* One call that needs a live handle of `kind`. */
static ShikkiStatus use_as(enum Kind kind, uint64_t id) {
    size_t n = 0;
    switch (kind) {
    case RENDERER: return shikki_renderer_validation_message_count((ShikkiRenderer){id}, &n);
    case ENVIRONMENT:
        return shikki_scene_set_environment(probe_scene, (ShikkiEnvironment){id}, 1.0, 0.0);
    case MESH: return shikki_mesh_counts((ShikkiMesh){id}, &n, NULL);
    case MATERIAL: return shikki_material_validate((ShikkiMaterial){id});
    case SCENE: return shikki_scene_get_output((ShikkiScene){id}, NULL, NULL);
    default: return SHIKKI_STATUS_PANIC;
    }
}

static ShikkiStatus destroy_as(enum Kind kind, uint64_t id) {
    switch (kind) {
    case RENDERER: return shikki_renderer_destroy((ShikkiRenderer){id});
    case ENVIRONMENT: return shikki_environment_destroy((ShikkiEnvironment){id});
    case MESH: return shikki_mesh_destroy((ShikkiMesh){id});
    case MATERIAL: return shikki_material_destroy((ShikkiMaterial){id});
    case SCENE: return shikki_scene_destroy((ShikkiScene){id});
    default: return SHIKKI_STATUS_PANIC;
    }
}

/* A new object of `kind` (not a renderer: each one opens a Vulkan device). */
static ShikkiStatus make(enum Kind kind, uint64_t *id) {
    static const float rgb[6] = {1, 1, 1, 1, 1, 1};
    ShikkiStatus status = SHIKKI_STATUS_PANIC;
    switch (kind) {
    case ENVIRONMENT: {
        ShikkiEnvironment h = {0};
        status = shikki_environment_create_rgb(2, 1, rgb, &h);
        *id = h.id;
        break;
    }
    case MESH: {
        ShikkiMesh h = {0};
        status = shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, &h);
        *id = h.id;
        break;
    }
    case MATERIAL: {
        ShikkiMaterial h = {0};
        status = shikki_material_create_preset("smooth", &h);
        *id = h.id;
        break;
    }
    case SCENE: {
        ShikkiScene h = {0};
        status = shikki_scene_create(&h);
        *id = h.id;
        break;
    }
    default: break;
    }
    return status;
}

#define SLOT(id) ((id) & 0xffffffffULL)
#define GENERATION(id) ((id) >> 32)

/* `renderer` is live and stays live; everything made here is destroyed here. */
static void hostile_handles(ShikkiRenderer renderer) {
    char what[160];
    uint64_t live[KINDS] = {renderer.id};
    EXPECT(shikki_scene_create(&probe_scene), SHIKKI_STATUS_OK);
    for (int k = ENVIRONMENT; k < KINDS; k++) {
        snprintf(what, sizeof what, "make a %s", kind_names[k]);
        expect(what, make(k, &live[k]), SHIKKI_STATUS_OK);
    }

    /* Every kind where every other kind is expected, for a call and for destroy; the message
     * names the kind the handle really is. The object survives all of it. */
    for (int a = 0; a < KINDS; a++) {
        for (int b = 0; b < KINDS; b++) {
            if (a == b) continue;
            snprintf(what, sizeof what, "a %s used as a %s", kind_names[a], kind_names[b]);
            expect_message(what, use_as(b, live[a]), SHIKKI_STATUS_INVALID_HANDLE, kind_names[a]);
            snprintf(what, sizeof what, "a %s destroyed as a %s", kind_names[a], kind_names[b]);
            expect_message(what, destroy_as(b, live[a]), SHIKKI_STATUS_INVALID_HANDLE,
                           kind_names[a]);
        }
        snprintf(what, sizeof what, "the %s survives being passed as every other kind",
                 kind_names[a]);
        expect(what, use_as(a, live[a]), SHIKKI_STATUS_OK);
    }

    /* Forged ids: a future generation of a live slot, generation 0, a slot that does not exist,
     * all bits set, slot field 0 with a generation. */
    for (int k = 0; k < KINDS; k++) {
        const uint64_t id = live[k];
        const uint64_t forged[] = {SLOT(id) | (GENERATION(id) + 1) << 32,
                                   SLOT(id),
                                   0xfffffffeULL | GENERATION(id) << 32,
                                   UINT64_MAX,
                                   1ULL << 32};
        for (size_t i = 0; i < sizeof forged / sizeof forged[0]; i++) {
            snprintf(what, sizeof what, "forged %s %#llx used", kind_names[k],
                     (unsigned long long)forged[i]);
            expect(what, use_as(k, forged[i]), SHIKKI_STATUS_INVALID_HANDLE);
            snprintf(what, sizeof what, "forged %s %#llx destroyed", kind_names[k],
                     (unsigned long long)forged[i]);
            expect(what, destroy_as(k, forged[i]), SHIKKI_STATUS_INVALID_HANDLE);
        }
        snprintf(what, sizeof what, "the %s survives forged neighbours", kind_names[k]);
        expect(what, use_as(k, id), SHIKKI_STATUS_OK);
    }

    /* The zero handle ("none"): destroying it is a no-op like free(NULL); using it is an invalid
     * handle, except as an environment, where 0 means "no environment" (documented). */
    for (int k = 0; k < KINDS; k++) {
        snprintf(what, sizeof what, "destroy a zero %s", kind_names[k]);
        expect(what, destroy_as(k, 0), SHIKKI_STATUS_OK);
        snprintf(what, sizeof what, "use a zero %s", kind_names[k]);
        expect(what, use_as(k, 0), k == ENVIRONMENT ? SHIKKI_STATUS_OK : SHIKKI_STATUS_INVALID_HANDLE);
    }

    /* Use after destroy, double destroy, and a stale handle after its slot is reused: the slot
     * comes back with a new generation, and neither a call nor a destroy through the old handle
     * may reach the new object. */
    for (int k = ENVIRONMENT; k < KINDS; k++) {
        const uint64_t old = live[k];
        uint64_t fresh = 0;
        snprintf(what, sizeof what, "destroy a %s", kind_names[k]);
        expect(what, destroy_as(k, old), SHIKKI_STATUS_OK);
        snprintf(what, sizeof what, "use a %s after destroy", kind_names[k]);
        expect_message(what, use_as(k, old), SHIKKI_STATUS_INVALID_HANDLE, "was destroyed");
        snprintf(what, sizeof what, "destroy a %s twice", kind_names[k]);
        expect_message(what, destroy_as(k, old), SHIKKI_STATUS_INVALID_HANDLE, "was destroyed");
        snprintf(what, sizeof what, "make a %s in the freed slot", kind_names[k]);
        expect(what, make(k, &fresh), SHIKKI_STATUS_OK);
        snprintf(what, sizeof what, "the new %s reuses the slot with another generation",
                 kind_names[k]);
        expect_true(what, SLOT(fresh) == SLOT(old) && fresh != old);
        snprintf(what, sizeof what, "use a stale %s after its slot is reused", kind_names[k]);
        expect(what, use_as(k, old), SHIKKI_STATUS_INVALID_HANDLE);
        snprintf(what, sizeof what, "destroy a stale %s after its slot is reused", kind_names[k]);
        expect(what, destroy_as(k, old), SHIKKI_STATUS_INVALID_HANDLE);
        snprintf(what, sizeof what, "the new %s survives its stale predecessor", kind_names[k]);
        expect(what, use_as(k, fresh), SHIKKI_STATUS_OK);
        snprintf(what, sizeof what, "destroy the new %s", kind_names[k]);
        expect(what, destroy_as(k, fresh), SHIKKI_STATUS_OK);
    }
    EXPECT(shikki_scene_destroy(probe_scene), SHIKKI_STATUS_OK);
}

/* After `renderer` was destroyed: every renderer call fails cleanly, and once its slot is taken
 * by a material, the old renderer handle neither reaches nor frees the material. */
static void destroyed_renderer(ShikkiRenderer renderer, ShikkiScene scene) {
    size_t n = 0;
    uint8_t rgba[16 * 12 * 4];
    EXPECT(shikki_renderer_validation_message_count(renderer, &n), SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_render_rgba8(renderer, scene, rgba, sizeof rgba), SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_render_to_file(renderer, scene, "never.png"), SHIKKI_STATUS_INVALID_HANDLE);
    FILE *never = fopen("never.png", "rb");
    EXPECT_TRUE(never == NULL); /* a failed render leaves no file */
    if (never) fclose(never);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_INVALID_HANDLE);
    ShikkiMaterial tenant = {0};
    EXPECT(shikki_material_create_preset("rough", &tenant), SHIKKI_STATUS_OK);
    EXPECT_TRUE(SLOT(tenant.id) == SLOT(renderer.id) && tenant.id != renderer.id);
    EXPECT_MESSAGE(shikki_renderer_destroy(renderer), SHIKKI_STATUS_INVALID_HANDLE,
                   "was destroyed");
    EXPECT_MESSAGE(shikki_renderer_destroy((ShikkiRenderer){tenant.id}),
                   SHIKKI_STATUS_INVALID_HANDLE, "ShikkiMaterial");
    EXPECT(shikki_material_validate(tenant), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(tenant), SHIKKI_STATUS_OK);
}

/* ---- NULL out-pointers: each fails before any work, and leaves no object behind. ---------- */
static void null_out_pointers(void) {
    static const float rgb[6] = {1, 1, 1, 1, 1, 1};
    const size_t before = shikki_live_handle_count();
    ShikkiRendererOptions options = {.device_name = NULL, .validation = false};
    EXPECT_MESSAGE(shikki_renderer_create(&options, NULL), SHIKKI_STATUS_NULL_ARGUMENT, "`out`");
    EXPECT(shikki_renderer_create(NULL, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_environment_load("builtin:studio", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_environment_create_rgb(2, 1, rgb, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, NULL),
           SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, NULL, 24, &(ShikkiMesh){0}),
           SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_load("bowl.obj", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_load(NULL, &(ShikkiMesh){0}), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_create_builtin("sphere", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_mesh_create_builtin(NULL, &(ShikkiMesh){0}), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_material_create_toml("preset = \"smooth\"\n", NULL, NULL),
           SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_material_load("m.toml", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_material_load(NULL, &(ShikkiMaterial){0}), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_create_default(NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_create_toml("", NULL, NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_create_toml(NULL, NULL, &(ShikkiScene){0}), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_load("s.toml", NULL), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_load(NULL, &(ShikkiScene){0}), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT_TRUE(shikki_live_handle_count() == before);

    ShikkiMaterial material = {0};
    ShikkiScene scene = {0};
    EXPECT(shikki_material_create_preset("smooth", &material), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_create(&scene), SHIKKI_STATUS_OK);
    EXPECT_MESSAGE(shikki_material_set(material, NULL, "0.1"), SHIKKI_STATUS_NULL_ARGUMENT, "`key`");
    EXPECT_MESSAGE(shikki_material_set(material, "m", NULL), SHIKKI_STATUS_NULL_ARGUMENT, "`value`");
    const double v[3] = {0.0, 1.0, 0.0};
    EXPECT(shikki_scene_add_point_light(scene, NULL, v), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_set_camera(scene, NULL, v, NULL, 40.0), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_set_camera(scene, v, NULL, NULL, 40.0), SHIKKI_STATUS_NULL_ARGUMENT);
    EXPECT(shikki_scene_set_background(scene, SHIKKI_BACKGROUND_COLOR, NULL),
           SHIKKI_STATUS_NULL_ARGUMENT);
    /* Documented as optional: NULL is fine. */
    EXPECT(shikki_scene_set_background(scene, SHIKKI_BACKGROUND_TRANSPARENT, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_get_output(scene, NULL, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_fresnel_file(material, NULL), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(material), SHIKKI_STATUS_OK);
}

/* ---- Strings that are not UTF-8 (every string argument is NUL-terminated; none takes a
 * length): INVALID_ARGUMENT naming the argument, nothing made. ----------------------------- */
static void invalid_utf8(ShikkiRenderer renderer, ShikkiScene scene) {
    const char *bad = "smo\xff\xfeoth"; /* 0xFF never occurs in UTF-8 */
    const char *truncated = "bowl\xe3\x81";  /* a 3-byte sequence cut short by the NUL */
    const size_t before = shikki_live_handle_count();
    ShikkiMaterial material = {0};
    ShikkiMesh mesh = {0};
    ShikkiScene made = {0};
    ShikkiEnvironment environment = {0};
    ShikkiRendererOptions options = {.device_name = bad, .validation = false};
    EXPECT_MESSAGE(shikki_renderer_create(&options, &(ShikkiRenderer){0}),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "UTF-8");
    EXPECT_MESSAGE(shikki_material_create_preset(bad, &material), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "`name`");
    EXPECT(shikki_material_create_toml(bad, NULL, &material), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_MESSAGE(shikki_material_create_toml("preset = \"smooth\"\n", truncated, &material),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "`base_dir`");
    EXPECT(shikki_material_load(truncated, &material), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_mesh_create_builtin(truncated, &mesh), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_mesh_load(bad, &mesh), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_environment_load(bad, &environment), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_create_toml(bad, NULL, &made), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_load(truncated, &made), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_MESSAGE(shikki_render_to_file(renderer, scene, bad), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "`path`");
    float pixel[4] = {0, 0, 0, 1};
    EXPECT(shikki_image_write(pixel, 4, 1, 1, 0.0f, SHIKKI_TONE_CURVE_ACES, truncated),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_TRUE(shikki_live_handle_count() == before);

    EXPECT(shikki_material_create_preset("smooth", &material), SHIKKI_STATUS_OK);
    EXPECT_MESSAGE(shikki_material_set(material, bad, "0.1"), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "`key`");
    EXPECT_MESSAGE(shikki_material_set(material, "m", truncated), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "`value`");
    EXPECT(shikki_material_set_fresnel_file(material, bad), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_validate(material), SHIKKI_STATUS_OK); /* unchanged by the failures */
    EXPECT(shikki_material_destroy(material), SHIKKI_STATUS_OK);
}

/* ---- Sizes far beyond the limits: refused before any caller memory is read (the arrays here
 * are tiny; reading as much as the sizes claim would crash) and before anything is allocated. */
static void huge_sizes(ShikkiRenderer renderer, ShikkiScene scene) {
    static const float rgb[3] = {1, 1, 1};
    float pixel[4] = {0, 0, 0, 1};
    uint8_t byte4[4] = {0};
    const size_t before = shikki_live_handle_count();
    ShikkiEnvironment environment = {0};
    ShikkiMesh mesh = {0};
    EXPECT_MESSAGE(shikki_environment_create_rgb(UINT32_MAX, UINT32_MAX, rgb, &environment),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "32768");
    EXPECT(shikki_environment_create_rgb(65536, 1, rgb, &environment),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_environment_create_rgb(32768, 16384, rgb, &environment), /* 2^29 pixels */
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_environment_create_rgb(0, 8, rgb, &environment), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_MESSAGE(shikki_mesh_create(octa_positions, NULL, SIZE_MAX, octa_indices, 24, &mesh),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "vertex_count");
    EXPECT(shikki_mesh_create(octa_positions, NULL, SIZE_MAX / 3, octa_indices, 24, &mesh),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_mesh_create(octa_positions, NULL, (size_t)1 << 40, octa_indices, 24, &mesh),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_MESSAGE(shikki_mesh_create(octa_positions, NULL, 6, octa_indices, SIZE_MAX - 2, &mesh),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "index_count");
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, octa_indices, (size_t)3 << 40, &mesh),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_mesh_create(octa_positions, NULL, 0, octa_indices, 0, &mesh),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_MESSAGE(shikki_scene_set_output(scene, UINT32_MAX, UINT32_MAX, 1),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "16384");
    EXPECT(shikki_scene_set_output(scene, 16385, 1, 1), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_output(scene, 1, 0, 1), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_render_rgba32f(renderer, scene, pixel, SIZE_MAX), SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT(shikki_render_rgba8(renderer, scene, byte4, SIZE_MAX / 2), SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT_MESSAGE(shikki_image_write(pixel, 4, UINT32_MAX, UINT32_MAX, 0.0f,
                                      SHIKKI_TONE_CURVE_ACES, "huge.png"),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "16384");
    EXPECT(shikki_image_write(pixel, SIZE_MAX, 1, 1, 0.0f, SHIKKI_TONE_CURVE_ACES, "huge.png"),
           SHIKKI_STATUS_BUFFER_SIZE);
    EXPECT(shikki_image_write(pixel, 0, 0, 0, 0.0f, SHIKKI_TONE_CURVE_ACES, "empty.png"),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    /* Non-finite numbers where a size or an amount is expected. */
    const double eye[3] = {0, 0, 3}, target[3] = {0, 0, 0}, inf3[3] = {INFINITY, 1, 1};
    EXPECT(shikki_scene_set_camera(scene, eye, target, NULL, NAN), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_camera(scene, eye, target, NULL, 1e308), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_add_point_light(scene, eye, inf3), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_scene_set_display(scene, INFINITY, SHIKKI_TONE_CURVE_ACES),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    ShikkiMaterial material = {0};
    EXPECT(shikki_material_create_preset("smooth", &material), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_set_beckmann_m(material, NAN), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set_lacquer_ratio(material, INFINITY), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set_beta_power(material, -INFINITY), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_set(material, "a", "1e999"), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT(shikki_material_validate(material), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(material), SHIKKI_STATUS_OK);
    FILE *written = fopen("huge.png", "rb");
    EXPECT_TRUE(written == NULL);
    if (written) fclose(written);
    EXPECT_TRUE(shikki_live_handle_count() == before);
}

/* ---- Values past what the renderer's f32 arithmetic carries (src/model/limits.rs) -----------
 * Each of these was accepted and drew black, or failed at the render naming the wrong thing
 * (a probe, 2026-12-06): now refused where it is given, naming the range. */
static void out_of_range_values(ShikkiScene scene, ShikkiMaterial material) {
    ShikkiMesh mesh = {0};
    EXPECT(shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, &mesh), SHIKKI_STATUS_OK);
    EXPECT_MESSAGE(shikki_material_set_beckmann_m(material, 1e-20), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "[0.001, 1]");
    EXPECT_MESSAGE(shikki_material_set_diffuse_a(material, 1e39), SHIKKI_STATUS_INVALID_ARGUMENT,
                   "1e6");
    EXPECT_MESSAGE(shikki_material_set_lacquer_law(material, 1e39, 0, 0),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e6");
    EXPECT(shikki_material_validate(material), SHIKKI_STATUS_OK); /* unchanged */
    const double up[3] = {0, 1, 0}, huge[3] = {1e39, 1e39, 1e39}, far_light[3] = {0, 1e16, 0};
    EXPECT_MESSAGE(shikki_scene_add_directional_light(scene, up, huge),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e20");
    EXPECT_MESSAGE(shikki_scene_add_point_light(scene, far_light, up),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e15");
    const double far_eye[3] = {0, 0, 1e39}, origin[3] = {0, 0, 0};
    const double eye[3] = {0, 0, 1 + 1e-9}, target[3] = {0, 0, 1};
    EXPECT_MESSAGE(shikki_scene_set_camera(scene, far_eye, origin, NULL, 40.0),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e15");
    EXPECT_MESSAGE(shikki_scene_set_camera(scene, eye, target, NULL, 40.0),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "differ");
    EXPECT_MESSAGE(shikki_scene_set_camera(scene, target, origin, NULL, 1e-300),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "fov");
    /* Column-major placements: flattened 1e30 : 1, collapsed, beyond f32. */
    const double flat[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1e-30, 0, 0, 0, 0, 1};
    const double collapsed[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
    const double far_away[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1e39, 0, 1};
    EXPECT_MESSAGE(shikki_scene_add_object(scene, mesh, material, flat),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "transform");
    EXPECT_MESSAGE(shikki_scene_add_object(scene, mesh, material, collapsed),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "transform");
    EXPECT_MESSAGE(shikki_scene_add_object(scene, mesh, material, far_away),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e15");
    /* An environment whose brightest pixel times the intensity is past 1e20. */
    const float bright[6] = {1e30f, 1e30f, 1e30f, 1, 1, 1};
    ShikkiEnvironment sun = {0};
    EXPECT(shikki_environment_create_rgb(2, 1, bright, &sun), SHIKKI_STATUS_OK);
    EXPECT_MESSAGE(shikki_scene_set_environment(scene, sun, 1.0, 0.0),
                   SHIKKI_STATUS_INVALID_ARGUMENT, "1e20");
    EXPECT(shikki_environment_destroy(sun), SHIKKI_STATUS_OK);
    /* A malformed mesh file is a parse error, as the header says, not an I/O error. */
    FILE *empty = fopen("empty.obj", "w");
    if (empty != NULL) {
        fputs("# no faces\nv 0 0 0\n", empty);
        fclose(empty);
    }
    ShikkiMesh none = {0};
    EXPECT(shikki_mesh_load("empty.obj", &none), SHIKKI_STATUS_PARSE_ERROR);
    remove("empty.obj");
    EXPECT(shikki_mesh_destroy(mesh), SHIKKI_STATUS_OK);
}

/* ---- Files at the output path --------------------------------------------------------------
 * A failed render leaves no file at its path, whatever failed (an earlier file there would pass
 * for its output); `shikki_image_write` refuses invalid arguments before it touches the path. */
static int exists(const char *path) {
    FILE *f = fopen(path, "r");
    if (f != NULL) fclose(f);
    return f != NULL;
}

static int file_holds(const char *path, const char *text) {
    char buffer[64] = {0};
    FILE *f = fopen(path, "r");
    if (f == NULL) return 0;
    size_t n = fread(buffer, 1, sizeof buffer - 1, f);
    fclose(f);
    return n == strlen(text) && memcmp(buffer, text, n) == 0;
}

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (f != NULL) {
        fputs(text, f);
        fclose(f);
    }
}

static void output_files(ShikkiRenderer renderer, ShikkiScene scene) {
    write_text("stale.png", "old");
    EXPECT(shikki_render_to_file((ShikkiRenderer){0}, scene, "stale.png"),
           SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT_TRUE(!exists("stale.png"));
    write_text("stale.png", "old");
    EXPECT(shikki_render_to_file(renderer, (ShikkiScene){0}, "stale.png"),
           SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT_TRUE(!exists("stale.png"));
    /* A path refused is left alone. */
    write_text("notes.txt", "mine");
    EXPECT(shikki_render_to_file(renderer, scene, "notes.txt"), SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_TRUE(file_holds("notes.txt", "mine"));
    remove("notes.txt");
    /* Invalid arguments to shikki_image_write: refused, the file as it was. */
    float pixels[2 * 2 * 4] = {0};
    pixels[5] = NAN;
    write_text("mine.png", "mine");
    EXPECT(shikki_image_write(pixels, 16, 2, 2, 0.0f, SHIKKI_TONE_CURVE_ACES, "mine.png"),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_TRUE(file_holds("mine.png", "mine"));
    pixels[5] = 0.0f;
    EXPECT(shikki_image_write(pixels, 16, 2, 2, NAN, SHIKKI_TONE_CURVE_ACES, "mine.png"),
           SHIKKI_STATUS_INVALID_ARGUMENT);
    EXPECT_TRUE(file_holds("mine.png", "mine"));
    remove("mine.png");
    /* A file name over 255 bytes: refused before rendering. */
    char long_name[300];
    memset(long_name, 'x', 252);
    strcpy(long_name + 252, ".png");
    EXPECT_MESSAGE(shikki_render_to_file(renderer, scene, long_name),
                   SHIKKI_STATUS_IO_ERROR, "256 bytes");
}

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
    /* A file the scene names but that cannot be read is an I/O failure at its line, not a parse
       error (it was PARSE_ERROR before 2026-12-06's probe of the left-alone cases). */
    EXPECT_MESSAGE(shikki_scene_create_toml("[[object]]\nmesh = \"/nonexistent/cup.obj\"\n", NULL,
                                            &bad_scene),
                   SHIKKI_STATUS_IO_ERROR, ":2: column 8: cannot read /nonexistent/cup.obj");
    EXPECT_MESSAGE(shikki_scene_create_toml("[[object]]\nmesh = \"builtin:sphere\"\n"
                                            "material = \"/nonexistent/red.toml\"\n",
                                            NULL, &bad_scene),
                   SHIKKI_STATUS_IO_ERROR, "cannot read /nonexistent/red.toml");

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
    hostile_handles(renderer);
    out_of_range_values(scene, material);
    output_files(renderer, scene);
    null_out_pointers();
    invalid_utf8(renderer, scene);
    huge_sizes(renderer, scene);
    /* The failures above left the scene as it was: it still renders the same bytes. */
    uint8_t again[16 * 12 * 4];
    EXPECT(shikki_render_rgba8(renderer, scene, again, sizeof again), SHIKKI_STATUS_OK);
    EXPECT_TRUE(memcmp(again, ldr, sizeof ldr) == 0);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, hdr, 16 * 12 * 4), SHIKKI_STATUS_INVALID_HANDLE);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_INVALID_HANDLE);
    destroyed_renderer(renderer, scene);

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
