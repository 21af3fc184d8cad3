/* threads — the thread-safety contract of docs/c-api.md ("Threads"), checked from C with pthreads:
 *
 * 1. two renderers on two threads render one shared scene at the same time: every image equals,
 *    byte for byte, the one rendered before on a single thread;
 * 2. two threads render with one renderer: the calls are serialised inside, both images equal it;
 * 3. a render while another thread keeps changing the scene's output size: each render returns
 *    the full image of one size (it renders a snapshot) or SHIKKI_STATUS_BUFFER_SIZE, never an
 *    image of one size in a buffer of another;
 * 4. two threads hammer create / use / destroy / failing calls in lock-step: each thread's
 *    shikki_last_error() holds its own message only, stale handles stay invalid while the
 *    other thread reuses their slots, and of two simultaneous destroys of one handle exactly
 *    one succeeds;
 * 5. a renderer and a scene destroyed while another thread renders with them: the render
 *    finishes (or reports INVALID_HANDLE if it came too late), nothing crashes or leaks.
 *
 * Run by ffi/tests/c_api.rs natively with the validation layer (zero messages), and under
 * valgrind, helgrind and ASan+UBSan. Prints one line per check; exit status = number of failures.
 */
#define _POSIX_C_SOURCE 200809L

#include <shikki.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Small: the program also runs under valgrind, where lavapipe is ~50× slower. */
enum { W = 64, H = 64, LEN = W * H * 4, HAMMER_ROUNDS = 200 };

static pthread_mutex_t report_lock = PTHREAD_MUTEX_INITIALIZER;
static int checks = 0, failures = 0;

static void check(const char *what, int ok, const char *detail) {
    pthread_mutex_lock(&report_lock);
    checks++;
    if (!ok) failures++;
    /* Passing checks of the hammer are counted, not printed: there are thousands. */
    if (!ok || detail != NULL) printf("%s %s%s%s\n", ok ? "ok  " : "FAIL", what,
                                      detail ? ": " : "", detail ? detail : "");
    pthread_mutex_unlock(&report_lock);
}

/* `status` must equal `want`; the message is shown on failure. */
static void expect(const char *what, ShikkiStatus status, ShikkiStatus want) {
    char detail[600];
    snprintf(detail, sizeof detail, "status %d (want %d) %s", (int)status, (int)want,
             shikki_last_error());
    check(what, status == want, status == want ? NULL : detail);
}

/* An octahedron: 6 vertices, 8 outward-facing (counter-clockwise) triangles. */
static const float octa_positions[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
static const uint32_t octa_indices[] = {0, 2, 4, 4, 2, 1, 1, 2, 5, 5, 2, 0,
                                        4, 3, 0, 1, 3, 4, 5, 3, 1, 0, 3, 5};

/* A coarse UV sphere (224 triangles, counter-clockwise seen from outside; normals left to the
 * library): builtin:sphere has 65,024 triangles, which under valgrind costs ~25 s a render. */
enum { RINGS = 8, SEGMENTS = 16, SPHERE_VERTICES = 2 + (RINGS - 1) * SEGMENTS,
       SPHERE_TRIANGLES = 2 * SEGMENTS * (RINGS - 1) };
static ShikkiMesh make_sphere(void) {
    float positions[3 * SPHERE_VERTICES];
    uint32_t indices[3 * SPHERE_TRIANGLES], *t = indices;
    const uint32_t bottom = SPHERE_VERTICES - 1;
    const double pi = 3.14159265358979323846;
    positions[0] = 0, positions[1] = 1, positions[2] = 0;
    for (int i = 1; i < RINGS; i++)
        for (int j = 0; j < SEGMENTS; j++) {
            float *p = positions + 3 * (1 + (i - 1) * SEGMENTS + j);
            double r = sin(pi * i / RINGS), phi = 2 * pi * j / SEGMENTS;
            p[0] = (float)(r * cos(phi)), p[1] = (float)cos(pi * i / RINGS);
            p[2] = (float)(r * sin(phi));
        }
    positions[3 * bottom] = 0, positions[3 * bottom + 1] = -1, positions[3 * bottom + 2] = 0;
#define RING(i, j) (uint32_t)(1 + ((i) - 1) * SEGMENTS + (j) % SEGMENTS)
    for (int j = 0; j < SEGMENTS; j++) {
        *t++ = 0, *t++ = RING(1, j + 1), *t++ = RING(1, j);
        *t++ = bottom, *t++ = RING(RINGS - 1, j), *t++ = RING(RINGS - 1, j + 1);
        for (int i = 1; i < RINGS - 1; i++) {
            *t++ = RING(i, j), *t++ = RING(i + 1, j + 1), *t++ = RING(i + 1, j);
            *t++ = RING(i, j), *t++ = RING(i, j + 1), *t++ = RING(i + 1, j + 1);
        }
    }
#undef RING
    ShikkiMesh mesh = {0};
    expect("sphere", shikki_mesh_create(positions, NULL, SPHERE_VERTICES, indices,
                                        3 * SPHERE_TRIANGLES, &mesh),
           SHIKKI_STATUS_OK);
    return mesh;
}

/* The sky every test scene shares: a renderer prefilters an environment once and reuses it for
 * every scene that names the same one, which keeps the valgrind run short. */
static ShikkiEnvironment make_sky(void) {
    enum { SKY_W = 16, SKY_H = 8 };
    float sky[SKY_W * SKY_H * 3];
    for (int j = 0; j < SKY_H; j++)
        for (int i = 0; i < SKY_W; i++) {
            float up = 1.0f - (j + 0.5f) / SKY_H, *p = sky + 3 * (j * SKY_W + i);
            p[0] = 0.2f + up, p[1] = 0.25f + up, p[2] = 0.3f + 1.2f * up + 0.01f * i;
        }
    ShikkiEnvironment environment = {0};
    expect("sky", shikki_environment_create_rgb(SKY_W, SKY_H, sky, &environment),
           SHIKKI_STATUS_OK);
    return environment;
}

/* The test scene: a lacquered sphere and an octahedron under the default lights and `sky`,
 * W × H with 4 samples. Every call builds the same scene. */
static ShikkiScene make_scene(ShikkiEnvironment sky) {
    ShikkiScene scene = {0};
    ShikkiMesh sphere = {0}, octa = {0};
    ShikkiMaterial red = {0}, black = {0};
    const double left[16] = {0.6, 0, 0, 0, 0, 0.6, 0, 0, 0, 0, 0.6, 0, -0.5, 0, 0, 1};
    const double right[16] = {0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0.6, 0, 0, 1};
    expect("scene", shikki_scene_create(&scene), SHIKKI_STATUS_OK);
    sphere = make_sphere();
    expect("octahedron", shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, &octa),
           SHIKKI_STATUS_OK);
    expect("red", shikki_material_create_preset("rough-red", &red), SHIKKI_STATUS_OK);
    expect("black", shikki_material_create_preset("smooth-black", &black), SHIKKI_STATUS_OK);
    expect("add sphere", shikki_scene_add_object(scene, sphere, red, left), SHIKKI_STATUS_OK);
    expect("add octahedron", shikki_scene_add_object(scene, octa, black, right), SHIKKI_STATUS_OK);
    expect("lights", shikki_scene_add_default_lights(scene), SHIKKI_STATUS_OK);
    expect("environment", shikki_scene_set_environment(scene, sky, 1.0, 30.0), SHIKKI_STATUS_OK);
    expect("output", shikki_scene_set_output(scene, W, H, 4), SHIKKI_STATUS_OK);
    /* The scene holds its own references. */
    shikki_mesh_destroy(sphere), shikki_mesh_destroy(octa);
    shikki_material_destroy(red), shikki_material_destroy(black);
    return scene;
}

static uint8_t reference[LEN];

/* Seconds since the previous call: each part's time is printed, to keep the valgrind run short. */
static double lap(void) {
    static struct timespec last;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    double seconds = (now.tv_sec - last.tv_sec) + (now.tv_nsec - last.tv_nsec) * 1e-9;
    last = now;
    return seconds;
}

/* ---- 1, 2, 5: renders on threads ---------------------------------------------------------- */

typedef struct {
    const char *name;
    ShikkiRenderer renderer;
    ShikkiScene scene;
    int renders;
    pthread_barrier_t *start;
    /* Filled by the thread. */
    int ok, invalid_handle;
} RenderJob;

static void *render_thread(void *arg) {
    RenderJob *job = arg;
    uint8_t *image = malloc(LEN);
    char what[160];
    if (job->start) pthread_barrier_wait(job->start);
    for (int i = 0; i < job->renders; i++) {
        memset(image, 0xA5, LEN);
        ShikkiStatus status = shikki_render_rgba8(job->renderer, job->scene, image, LEN);
        snprintf(what, sizeof what, "%s render %d", job->name, i);
        if (status == SHIKKI_STATUS_OK) {
            job->ok++;
            check(what, memcmp(image, reference, LEN) == 0,
                  "equals the single-threaded image byte for byte");
        } else {
            job->invalid_handle += status == SHIKKI_STATUS_INVALID_HANDLE;
            expect(what, status, SHIKKI_STATUS_INVALID_HANDLE);
        }
    }
    free(image);
    return NULL;
}

static void run_jobs(RenderJob *jobs, int count) {
    pthread_t threads[4];
    for (int i = 0; i < count; i++) pthread_create(&threads[i], NULL, render_thread, &jobs[i]);
    for (int i = 0; i < count; i++) pthread_join(threads[i], NULL);
}

/* ---- 3: a render while the output size changes -------------------------------------------- */

static atomic_int resize_done;

typedef struct {
    ShikkiScene scene;
    int changes;
} Resizer;

static void *resize_thread(void *arg) {
    Resizer *resizer = arg;
    while (!atomic_load(&resize_done)) {
        int small = resizer->changes++ % 2 == 0;
        ShikkiStatus status = shikki_scene_set_output(resizer->scene, small ? W / 2 : W,
                                                      small ? H / 2 : H, 4);
        if (status != SHIKKI_STATUS_OK) expect("resize", status, SHIKKI_STATUS_OK);
        /* Often enough to land inside every render, not so often that it starves it. */
        nanosleep(&(struct timespec){.tv_nsec = 100 * 1000}, NULL);
    }
    return NULL;
}

/* ---- 4: the create/destroy/last-error hammer ---------------------------------------------- */

typedef struct {
    int index;
    pthread_barrier_t *step;
} Hammer;

/* One material per round that both hammer threads destroy at once: exactly one may succeed. */
static ShikkiMaterial contested[HAMMER_ROUNDS];
static ShikkiStatus contested_status[2][HAMMER_ROUNDS];

static int contains(const char *text, const char *needle) { return strstr(text, needle) != NULL; }

static void *hammer_thread(void *arg) {
    Hammer *self = arg;
    static const float rgb[6] = {1, 2, 3, 4, 5, 6};
    char token[32], what[200], kept[600];
    for (int round = 0; round < HAMMER_ROUNDS; round++) {
        /* A failure whose message only this thread, in this round, can produce ("m" must be in
         * (0, 1]; the value is quoted in the message). */
        snprintf(token, sizeof token, "%d%06d", 7 + self->index, round);
        ShikkiMaterial material = {0};
        expect("material", shikki_material_create_preset("smooth", &material), SHIKKI_STATUS_OK);
        check("a success leaves an empty message", shikki_last_error()[0] == '\0', NULL);
        expect("bad m", shikki_material_set(material, "m", token), SHIKKI_STATUS_INVALID_ARGUMENT);
        const char *message = shikki_last_error();
        snprintf(kept, sizeof kept, "%s", message);
        snprintf(what, sizeof what, "thread %d round %d: own message", self->index, round);
        check(what, contains(kept, token), contains(kept, token) ? NULL : kept);

        /* The other thread fails and succeeds in between. */
        pthread_barrier_wait(self->step);
        snprintf(what, sizeof what, "thread %d round %d: message unchanged by the other thread",
                 self->index, round);
        /* The pointer from before is still valid (no shikki_* call on this thread since). */
        int same = strcmp(message, kept) == 0 && strcmp(shikki_last_error(), kept) == 0;
        check(what, same, same ? NULL : shikki_last_error());

        /* Create, use, destroy every cheap kind; the stale handles stay invalid while the other
         * thread is taking the freed slots. */
        ShikkiMesh mesh = {0};
        ShikkiEnvironment environment = {0};
        ShikkiScene scene = {0};
        expect("mesh", shikki_mesh_create(octa_positions, NULL, 6, octa_indices, 24, &mesh),
               SHIKKI_STATUS_OK);
        expect("environment", shikki_environment_create_rgb(2, 1, rgb, &environment),
               SHIKKI_STATUS_OK);
        expect("scene", shikki_scene_create(&scene), SHIKKI_STATUS_OK);
        expect("add", shikki_scene_add_object(scene, mesh, material, NULL), SHIKKI_STATUS_OK);
        expect("set environment", shikki_scene_set_environment(scene, environment, 1.0, 0.0),
               SHIKKI_STATUS_OK);
        expect("wrong kind", shikki_scene_clear_lights((ShikkiScene){mesh.id}),
               SHIKKI_STATUS_INVALID_HANDLE);
        expect("destroy mesh", shikki_mesh_destroy(mesh), SHIKKI_STATUS_OK);
        expect("destroy environment", shikki_environment_destroy(environment), SHIKKI_STATUS_OK);
        expect("destroy material", shikki_material_destroy(material), SHIKKI_STATUS_OK);
        pthread_barrier_wait(self->step);
        contested_status[self->index][round] = shikki_material_destroy(contested[round]);
        expect("stale mesh", shikki_mesh_counts(mesh, NULL, NULL), SHIKKI_STATUS_INVALID_HANDLE);
        expect("stale material", shikki_material_destroy(material), SHIKKI_STATUS_INVALID_HANDLE);
        expect("stale environment",
               shikki_scene_set_environment(scene, environment, 1.0, 0.0),
               SHIKKI_STATUS_INVALID_HANDLE);
        expect("destroy scene", shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
        expect("destroy scene twice", shikki_scene_destroy(scene), SHIKKI_STATUS_INVALID_HANDLE);
        check("the last failure's message is this thread's",
              contains(shikki_last_error(), "ShikkiScene handle"), NULL);
    }
    return NULL;
}

int main(void) {
    const char *validation_env = getenv("SHIKKI_VALIDATION");
    ShikkiRendererOptions options = {
        .device_name = NULL,
        .validation = validation_env != NULL && strcmp(validation_env, "1") == 0,
    };
    ShikkiRenderer a = {0}, b = {0};
    lap();
    expect("renderer a", shikki_renderer_create(&options, &a), SHIKKI_STATUS_OK);
    expect("renderer b", shikki_renderer_create(&options, &b), SHIKKI_STATUS_OK);
    printf("info two renderers: %.1f s\n", lap());
    ShikkiEnvironment sky = make_sky();
    ShikkiScene scene = make_scene(sky);
    expect("reference render (one thread)", shikki_render_rgba8(a, scene, reference, LEN),
           SHIKKI_STATUS_OK);
    int covered = 0;
    for (int i = 0; i < W * H; i++) covered += reference[4 * i + 3] != 0;
    check("the reference image shows the objects", covered > W * H / 10, NULL);

    printf("info scene and reference render: %.1f s\n", lap());
    /* 1. Two renderers, two threads, one scene, at the same time. */
    pthread_barrier_t start;
    pthread_barrier_init(&start, NULL, 2);
    RenderJob parallel[2] = {{"renderer a on thread 1", a, scene, 2, &start, 0, 0},
                             {"renderer b on thread 2", b, scene, 2, &start, 0, 0}};
    run_jobs(parallel, 2);
    check("parallel renders all succeeded", parallel[0].ok == 2 && parallel[1].ok == 2, NULL);

    printf("info two renderers in parallel: %.1f s\n", lap());
    /* 2. One renderer, two threads: serialised inside. */
    RenderJob shared[2] = {{"renderer a shared, thread 1", a, scene, 2, &start, 0, 0},
                           {"renderer a shared, thread 2", a, scene, 2, &start, 0, 0}};
    run_jobs(shared, 2);
    check("shared-renderer renders all succeeded", shared[0].ok == 2 && shared[1].ok == 2, NULL);
    pthread_barrier_destroy(&start);
    printf("info one renderer shared: %.1f s\n", lap());

    /* 3. Renders while another thread flips the output size: a full W × H image (== reference)
     * or BUFFER_SIZE; a half-size image in the full-size buffer would differ from reference. */
    ShikkiScene resized = make_scene(sky);
    Resizer resizer = {resized, 0};
    pthread_t resize;
    atomic_store(&resize_done, 0);
    pthread_create(&resize, NULL, resize_thread, &resizer);
    uint8_t *image = malloc(LEN);
    int fitted = 0, refused = 0;
    /* Refusals are instant, so keep trying (a refusal waits as long as a size change takes)
     * until three renders have run alongside the size changes. */
    while (fitted < 3 && refused < 100000) {
        if (fitted + refused > 0) nanosleep(&(struct timespec){.tv_nsec = 50 * 1000}, NULL);
        memset(image, 0xA5, LEN);
        ShikkiStatus status = shikki_render_rgba8(b, resized, image, LEN);
        if (status == SHIKKI_STATUS_OK) {
            fitted++;
            check("a render during resizing holds one whole image",
                  memcmp(image, reference, LEN) == 0, "full size, equal to the reference");
        } else {
            refused++;
            if (status != SHIKKI_STATUS_BUFFER_SIZE)
                expect("a render during resizing", status, SHIKKI_STATUS_BUFFER_SIZE);
        }
    }
    check("three renders ran while the size changed", fitted == 3, NULL);
    atomic_store(&resize_done, 1);
    pthread_join(resize, NULL);
    free(image);
    printf("info resizing: %d size changes; %d renders fitted, %d refused (BUFFER_SIZE)\n",
           resizer.changes, fitted, refused);
    expect("destroy resized scene", shikki_scene_destroy(resized), SHIKKI_STATUS_OK);

    printf("info renders while resizing: %.1f s\n", lap());
    /* 4. The hammer. */
    pthread_barrier_t step;
    pthread_barrier_init(&step, NULL, 2);
    for (int r = 0; r < HAMMER_ROUNDS; r++)
        expect("contested material", shikki_material_create_preset("rough", &contested[r]),
               SHIKKI_STATUS_OK);
    Hammer hammers[2] = {{0, &step}, {1, &step}};
    pthread_t hammer[2];
    for (int i = 0; i < 2; i++) pthread_create(&hammer[i], NULL, hammer_thread, &hammers[i]);
    for (int i = 0; i < 2; i++) pthread_join(hammer[i], NULL);
    pthread_barrier_destroy(&step);
    int one_winner = 1;
    for (int r = 0; r < HAMMER_ROUNDS; r++) {
        ShikkiStatus x = contested_status[0][r], y = contested_status[1][r];
        one_winner &= (x == SHIKKI_STATUS_OK && y == SHIKKI_STATUS_INVALID_HANDLE) ||
                      (y == SHIKKI_STATUS_OK && x == SHIKKI_STATUS_INVALID_HANDLE);
    }
    check("a handle destroyed by two threads at once: one OK, one INVALID_HANDLE", one_winner,
          NULL);
    check("hammer: handles left alive", shikki_live_handle_count() == 4, NULL); /* a, b, sky, scene */

    printf("info hammer: %.1f s\n", lap());
    size_t messages = 99;
    expect("validation count a", shikki_renderer_validation_message_count(a, &messages),
           SHIKKI_STATUS_OK);
    check("renderer a: no validation message", messages == 0, NULL);
    expect("validation count b", shikki_renderer_validation_message_count(b, &messages),
           SHIKKI_STATUS_OK);
    check("renderer b: no validation message", messages == 0, NULL);

    /* 5. Destroy a renderer and a scene while another thread renders with them. */
    ShikkiScene doomed = make_scene(sky);
    pthread_barrier_init(&start, NULL, 2);
    RenderJob victim = {"render while destroyed", b, doomed, 2, &start, 0, 0};
    pthread_t render;
    pthread_create(&render, NULL, render_thread, &victim);
    pthread_barrier_wait(&start);
    /* Most likely inside the first render (a render takes ~10 ms natively, ~0.5 s
     * under valgrind); either way the statuses below are the contract. */
    nanosleep(&(struct timespec){.tv_nsec = 2 * 1000 * 1000}, NULL);
    expect("destroy the renderer in use", shikki_renderer_destroy(b), SHIKKI_STATUS_OK);
    expect("destroy the scene in use", shikki_scene_destroy(doomed), SHIKKI_STATUS_OK);
    pthread_join(render, NULL);
    pthread_barrier_destroy(&start);
    printf("info destroyed in use: %d render(s) finished, %d found the handle gone\n", victim.ok,
           victim.invalid_handle);
    check("every render finished or found its handle gone",
          victim.ok + victim.invalid_handle == 2, NULL);

    expect("destroy scene", shikki_scene_destroy(scene), SHIKKI_STATUS_OK);
    expect("destroy sky", shikki_environment_destroy(sky), SHIKKI_STATUS_OK);
    expect("destroy renderer a", shikki_renderer_destroy(a), SHIKKI_STATUS_OK);
    printf("info destroy in use and teardown: %.1f s\n", lap());
    check("no handle left alive", shikki_live_handle_count() == 0, NULL);
    printf("%d checks, %d failed\n", checks, failures);
    return failures;
}
