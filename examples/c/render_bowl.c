/* render_bowl — render shikki's default scene (two lacquer bowls on the studio environment)
 * from C: into memory as linear RGBA32F, then to a PNG through the library.
 *
 *   render_bowl [OUTPUT.png [SIZE]]       (default: bowls.png, 256)
 *
 * SHIKKI_VALIDATION=1 turns the Vulkan validation layer on; the program then fails if the
 * layer reported anything. Exit status 0 on success, 1 on any error (the message is printed).
 */
#include <shikki.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Prints the failed call and the library's message, and jumps to cleanup. */
#define CHECK(call)                                                                  \
    do {                                                                             \
        ShikkiStatus status_ = (call);                                               \
        if (status_ != SHIKKI_STATUS_OK) {                                           \
            fprintf(stderr, "%s failed (status %d): %s\n", #call, (int)status_,      \
                    shikki_last_error());                                            \
            goto cleanup;                                                            \
        }                                                                            \
    } while (0)

int main(int argc, char **argv) {
    const char *output = argc > 1 ? argv[1] : "bowls.png";
    unsigned size = argc > 2 ? (unsigned)strtoul(argv[2], NULL, 10) : 256;
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    int exit_code = 1;

    /* Zero-initialised handles are "no object": destroying them is a no-op. */
    ShikkiRenderer renderer = {0};
    ShikkiScene scene = {0};
    float *pixels = NULL;

    printf("shikki %s\n", shikki_version());

    ShikkiRendererOptions options = {
        .device_name = NULL, /* the first Vulkan device (lavapipe on a machine without GPU) */
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    CHECK(shikki_renderer_create(&options, &renderer));

    CHECK(shikki_scene_create_default(&scene));
    /* One sample per pixel keeps the example fast; the default is 4. */
    CHECK(shikki_scene_set_output(scene, size, size, 1));

    uint32_t width = 0, height = 0;
    CHECK(shikki_scene_get_output(scene, &width, &height));
    size_t len = (size_t)width * height * 4;
    pixels = malloc(len * sizeof(float));
    if (pixels == NULL) {
        fprintf(stderr, "out of memory for %ux%u pixels\n", width, height);
        goto cleanup;
    }

    /* Linear radiance, premultiplied by coverage, row 0 at the top. */
    CHECK(shikki_render_rgba32f(renderer, scene, pixels, len));

    /* 0 EV and the ACES curve: the scene file's defaults. */
    CHECK(shikki_image_write(pixels, len, width, height, 0.0f, SHIKKI_TONE_CURVE_ACES, output));

    size_t messages = 0;
    CHECK(shikki_renderer_validation_message_count(renderer, &messages));
    if (messages != 0) {
        fprintf(stderr, "the validation layer reported %zu message(s)\n", messages);
        goto cleanup;
    }
    printf("wrote %s (%ux%u, validation %s, %zu message(s))\n", output, width, height,
           options.validation ? "on" : "off", messages);
    exit_code = 0;

cleanup:
    free(pixels);
    shikki_scene_destroy(scene);
    shikki_renderer_destroy(renderer);
    if (exit_code == 0 && shikki_live_handle_count() != 0) {
        fprintf(stderr, "%zu handle(s) still alive\n", shikki_live_handle_count());
        exit_code = 1;
    }
    return exit_code;
}
