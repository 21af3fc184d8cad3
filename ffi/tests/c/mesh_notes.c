/* mesh_notes — what the mesh loader changed in a file (a degenerate triangle, a line element,
 * generated normals) reaches the program through the renderer's warning callback, once per
 * renderer and file, for a mesh loaded with shikki_mesh_load and for one a scene TOML names.
 * A mesh made from arrays says nothing. Run by ffi/tests/c_api.rs in its output folder. Prints
 * one line per check; exit status = number of failed checks.
 */
#include "check.h"

#include <stdint.h>
#include <stdlib.h>

enum { SIDE = 8, LEN = SIDE * SIDE * 4 };

/* The warnings that name the mesh file, and the last one. */
typedef struct {
    int naming_file;
    int total;
    char last[512];
} Seen;

static void on_warning(void *user, const char *message) {
    Seen *seen = user;
    seen->total += 1;
    if (strstr(message, "tri.obj") != NULL) {
        seen->naming_file += 1;
        snprintf(seen->last, sizeof seen->last, "%s", message);
    }
}

static const char *const scene_toml = "environment = \"none\"\n"
                                      "[[object]]\n"
                                      "mesh = \"tri.obj\"\n"
                                      "[output]\n"
                                      "size = [8, 8]\n"
                                      "samples = 1\n";

int main(void) {
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    FILE *file = fopen("tri.obj", "w");
    if (!file) {
        printf("FAIL cannot write tri.obj\n");
        return 1;
    }
    /* One good triangle, one degenerate, one line element; no normals. */
    fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 2\nl 1 2\n", file);
    fclose(file);
    float *pixels = calloc(LEN, sizeof(float));
    if (!pixels) {
        printf("FAIL out of memory\n");
        return 1;
    }

    ShikkiMesh loaded = {0}, from_arrays = {0};
    ShikkiMaterial material = {0};
    ShikkiScene scene = {0}, plain = {0}, named = {0};
    ShikkiRenderer renderer = {0}, second = {0};
    EXPECT(shikki_mesh_load("tri.obj", &loaded), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_create_preset("smooth-red", &material), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_create_toml("environment = \"none\"\n[output]\nsize = [8, 8]\n"
                                    "samples = 1\n",
                                    NULL, &scene),
           SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_add_object(scene, loaded, material, NULL), SHIKKI_STATUS_OK);

    Seen seen = {0, 0, ""};
    EXPECT(shikki_renderer_create(&options, &renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_renderer_set_warning_callback(renderer, on_warning, &seen), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, pixels, LEN), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(renderer, scene, pixels, LEN), SHIKKI_STATUS_OK);
    printf("info %d warning(s), %d naming tri.obj: %s\n", seen.total, seen.naming_file,
           seen.last);
    EXPECT_TRUE(seen.naming_file == 1);
    EXPECT_TRUE(strstr(seen.last, "degenerate") != NULL);
    EXPECT_TRUE(strstr(seen.last, "normals") != NULL);

    /* The same triangle from arrays: nothing to say about a file. */
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t indices[3] = {0, 1, 2};
    EXPECT(shikki_mesh_create(positions, NULL, 3, indices, 3, &from_arrays), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_create_toml("environment = \"none\"\n[output]\nsize = [8, 8]\n"
                                    "samples = 1\n",
                                    NULL, &plain),
           SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_add_object(plain, from_arrays, material, NULL), SHIKKI_STATUS_OK);
    seen = (Seen){0, 0, ""};
    EXPECT(shikki_render_rgba32f(renderer, plain, pixels, LEN), SHIKKI_STATUS_OK);
    EXPECT_TRUE(seen.naming_file == 0);

    /* A scene TOML that names the file: said by a renderer that has not said it. */
    EXPECT(shikki_scene_create_toml(scene_toml, ".", &named), SHIKKI_STATUS_OK);
    EXPECT(shikki_renderer_create(&options, &second), SHIKKI_STATUS_OK);
    EXPECT(shikki_renderer_set_warning_callback(second, on_warning, &seen), SHIKKI_STATUS_OK);
    EXPECT(shikki_render_rgba32f(second, named, pixels, LEN), SHIKKI_STATUS_OK);
    printf("info scene TOML: %d warning(s) naming tri.obj: %s\n", seen.naming_file, seen.last);
    EXPECT_TRUE(seen.naming_file == 1);
    EXPECT_TRUE(strstr(seen.last, "degenerate") != NULL);

    size_t messages = 99;
    EXPECT(shikki_renderer_validation_message_count(renderer, &messages), SHIKKI_STATUS_OK);
    EXPECT_TRUE(messages == 0);
    EXPECT(shikki_renderer_validation_message_count(second, &messages), SHIKKI_STATUS_OK);
    EXPECT_TRUE(messages == 0);
    EXPECT(shikki_renderer_destroy(second), SHIKKI_STATUS_OK);
    EXPECT(shikki_renderer_destroy(renderer), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(named), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(plain), SHIKKI_STATUS_OK);
    EXPECT(shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    EXPECT(shikki_mesh_destroy(from_arrays), SHIKKI_STATUS_OK);
    EXPECT(shikki_mesh_destroy(loaded), SHIKKI_STATUS_OK);
    EXPECT(shikki_material_destroy(material), SHIKKI_STATUS_OK);
    EXPECT_TRUE(shikki_live_handle_count() == 0);
    free(pixels);
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
