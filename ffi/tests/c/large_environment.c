/* large_environment — the C API prepares environments exactly as the CLI does, so an 8192 × 4096
 * HDRI that the CLI renders on lavapipe renders here too (its prefilter face is clamped to what
 * the device holds in one buffer); the environment disk cache hands a second renderer the same
 * pixels; warnings reach the program's callback, once per map, with the renderer unlocked, and
 * are never printed by the library. Run by ffi/tests/c_api.rs, which writes both maps and
 * compares OUT.png with the Rust API's render of the same scene.
 *
 *   large_environment LARGE.hdr BAD_PIXELS.exr CACHE_DIR OUT.png SIZE
 *
 * Prints one line per check; exit status = number of failed checks.
 */
#define _POSIX_C_SOURCE 200809L

#include <shikki.h>

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int failures = 0;
static int checks = 0;

static void check(const char *what, int ok) {
    checks++;
    if (!ok) failures++;
    printf("%s %s\n", ok ? "ok  " : "FAIL", what);
}

static void expect(const char *what, ShikkiStatus status) {
    checks++;
    if (status != SHIKKI_STATUS_OK) failures++;
    printf("%s %s: status %d: %s\n", status == SHIKKI_STATUS_OK ? "ok  " : "FAIL", what,
           (int)status, shikki_last_error());
}

static double lap(void) {
    static struct timespec last;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    double seconds =
        (double)(now.tv_sec - last.tv_sec) + 1e-9 * (double)(now.tv_nsec - last.tv_nsec);
    last = now;
    return seconds;
}

/* What the warning callback saw, and the renderer it calls back into. */
typedef struct {
    int count;
    char last[1024];
    ShikkiRenderer renderer;
    int callback_calls_ok;
} Warnings;

static void on_warning(void *user_data, const char *message) {
    Warnings *warnings = user_data;
    warnings->count++;
    snprintf(warnings->last, sizeof warnings->last, "%s", message);
    printf("info warning: %s\n", message);
    /* The renderer is unlocked during the callback: a call on it returns instead of waiting for
     * the render that is calling us. A failing call here must not become the render's error. */
    size_t n = 0;
    ShikkiStatus on_renderer = shikki_renderer_validation_message_count(warnings->renderer, &n);
    ShikkiStatus failing = shikki_mesh_counts((ShikkiMesh){0}, &n, NULL);
    warnings->callback_calls_ok =
        on_renderer == SHIKKI_STATUS_OK && failing == SHIKKI_STATUS_INVALID_HANDLE;
}

static int cache_files(const char *dir) {
    DIR *d = opendir(dir);
    if (d == NULL) return 0;
    int n = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t len = strlen(e->d_name);
        n += len > 7 && strcmp(e->d_name + len - 7, ".shkenv") == 0;
    }
    closedir(d);
    return n;
}

static ShikkiRenderer make_renderer(const ShikkiRendererOptions *options, const char *cache_dir,
                                    Warnings *warnings) {
    ShikkiRenderer renderer = {0};
    expect("create a renderer", shikki_renderer_create(options, &renderer));
    warnings->renderer = renderer;
    expect("set the warning callback",
           shikki_renderer_set_warning_callback(renderer, on_warning, warnings));
    expect("set the environment cache", shikki_renderer_set_environment_cache(renderer, cache_dir));
    return renderer;
}

static size_t validation_messages(ShikkiRenderer renderer) {
    size_t n = 0;
    expect("validation message count", shikki_renderer_validation_message_count(renderer, &n));
    return n;
}

/* The map with NaN/negative pixels: one warning for its first render, none for the next. */
static void check_warnings(ShikkiRenderer renderer, ShikkiScene scene, const char *bad_path,
                           Warnings *warnings, uint8_t *pixels, size_t len) {
    ShikkiEnvironment bad = {0};
    expect("load the map with negative pixels", shikki_environment_load(bad_path, &bad));
    expect("light the scene with it", shikki_scene_set_environment(scene, bad, 1.0, 0.0));
    int before = warnings->count;
    expect("render with it", shikki_render_rgba8(renderer, scene, pixels, len));
    check("the callback was told of the replaced pixels, once",
          warnings->count == before + 1 && strstr(warnings->last, "were replaced by 0") != NULL &&
              strstr(warnings->last, bad_path) != NULL);
    check("the callback could call the library, this renderer included",
          warnings->callback_calls_ok);
    check("the callback's failed call is not the render's error", shikki_last_error()[0] == '\0');
    expect("render with it again", shikki_render_rgba8(renderer, scene, pixels, len));
    check("no second warning for the same map", warnings->count == before + 1);
    expect("remove the callback", shikki_renderer_set_warning_callback(renderer, NULL, NULL));
    expect("destroy the map", shikki_environment_destroy(bad));
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: %s LARGE.hdr BAD_PIXELS.exr CACHE_DIR OUT.png SIZE\n", argv[0]);
        return 2;
    }
    const char *large_path = argv[1], *bad_path = argv[2], *cache_dir = argv[3];
    const char *png_path = argv[4];
    uint32_t size = (uint32_t)strtoul(argv[5], NULL, 10);
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    size_t len = (size_t)size * size * 4;
    uint8_t *first = malloc(len), *second = malloc(len);
    Warnings warnings = {0};

    lap();
    ShikkiEnvironment large = {0};
    expect("load the 8192 × 4096 map", shikki_environment_load(large_path, &large));
    ShikkiScene scene = {0};
    expect("the default scene", shikki_scene_create_default(&scene));
    expect("lit by the large map", shikki_scene_set_environment(scene, large, 1.0, 0.0));
    expect("small output", shikki_scene_set_output(scene, size, size, 1));
    printf("info load the map: %.1f s\n", lap());

    ShikkiRenderer a = make_renderer(&options, cache_dir, &warnings);
    expect("render (prefilter, store in the cache)", shikki_render_rgba8(a, scene, first, len));
    printf("info first render, prefilter and cache store: %.1f s\n", lap());
    expect("write the PNG", shikki_render_to_file(a, scene, png_path));
    /* The map's layers, and its bright split's two residuals: the default scene traces rays, and
       a ray-traced `paper` draw reads the split for the hidden environment's control variate. */
    check("three cache files: the map and its bright split's two residuals",
          cache_files(cache_dir) == 3);
    check("no warning for a clean map", warnings.count == 0);
    check("renderer a: no validation messages", validation_messages(a) == 0);
    expect("destroy renderer a", shikki_renderer_destroy(a));

    ShikkiRenderer b = make_renderer(&options, cache_dir, &warnings);
    lap();
    expect("render on a second renderer (from the cache)",
           shikki_render_rgba8(b, scene, second, len));
    printf("info second renderer's render, from the disk cache: %.1f s\n", lap());
    check("the cached environment gives the same bytes", memcmp(first, second, len) == 0);
    check("still three cache files", cache_files(cache_dir) == 3);
    check_warnings(b, scene, bad_path, &warnings, second, len);
    check("renderer b: no validation messages", validation_messages(b) == 0);

    expect("destroy renderer b", shikki_renderer_destroy(b));
    expect("destroy the scene", shikki_scene_destroy(scene));
    expect("destroy the large map", shikki_environment_destroy(large));
    check("no handle left alive", shikki_live_handle_count() == 0);
    free(first);
    free(second);
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
