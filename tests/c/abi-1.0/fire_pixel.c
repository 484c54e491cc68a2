/* A complete C host of the fire, written from firemedium.h alone: load the plugin, create a fire from a dataset,
 * look through it along a fan of rays (luminance from the plugin's own colour weights), then build its fire
 * light and estimate the light it sends to a point beside it.
 *
 *   cc -std=c99 -I plugin/abi/include plugin/abi/examples/fire_pixel.c -ldl -o fire_pixel
 *   ./fire_pixel target/release/libfiremedium_plugin.so scenes/campfire/campfire.vdb
 *
 * (tests/c_header.rs compiles and runs it.) */
#include "firemedium.h"
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

static const FmApi *api;

/* Prints the plugin's message for a failed call and exits. */
static void check(FmStatus s, const char *what) {
    if (s == FM_OK) return;
    char msg[1024];
    api->last_error(msg, sizeof msg);
    fprintf(stderr, "fire_pixel: %s: %s (status %d)\n", what, msg, s);
    exit(1);
}

/* xorshift64: uniform numbers in [0, 1). */
static double uniform(uint64_t *state) {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return (double)(*state >> 11) / 9007199254740992.0;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: fire_pixel PLUGIN DATASET.vdb\n");
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "fire_pixel: %s\n", dlerror());
        return 1;
    }
    FmEntry entry = (FmEntry)dlsym(lib, FIREMEDIUM_ENTRY_SYMBOL);
    if (!entry) {
        fprintf(stderr, "fire_pixel: %s exports no %s\n", argv[1], FIREMEDIUM_ENTRY_SYMBOL);
        return 1;
    }
    api = entry();
    if (!fm_api_compatible(api)) {
        fprintf(stderr, "fire_pixel: the plugin speaks ABI %u.%u, this host needs %u.%u\n", api->abi_major,
                api->abi_minor, FM_ABI_MAJOR, FM_ABI_MINOR);
        return 1;
    }

    /* The fire: the dataset's density (a soot volume fraction) and temperature (K), propane soot. */
    const char *dataset = argv[2], *fuel = "propane";
    FmParam params[2] = {{"dataset", FM_TYPE_STRING, 1, &dataset}, {"fuel", FM_TYPE_STRING, 1, &fuel}};
    FmCreateInfo create = {.struct_size = sizeof create};
    create.params = params;
    create.count = 2;
    FmVolume *fire = NULL;
    check(api->volume_create(&create, &fire), "volume_create");
    FmVolumeInfo info = {.struct_size = sizeof info};
    check(api->volume_info(fire, &info), "volume_info");
    size_t c = info.channels;
    printf("fire: %zu channels over %g-%g nm\n", c, info.lambda_min, info.lambda_max);
    double *xyz = malloc(3 * c * sizeof(double));
    check(api->volume_channel_xyz(fire, xyz, 3 * c), "volume_channel_xyz");

    /* A fan of 9 rays across the box, a third of the way up: radiance and transmittance, 9 * c floats each. */
    enum { FAN = 9 };
    FmRay rays[FAN];
    double z = info.bounds_min[2] + 0.3 * (info.bounds_max[2] - info.bounds_min[2]);
    for (int i = 0; i < FAN; i++) {
        double x = info.bounds_min[0] + (info.bounds_max[0] - info.bounds_min[0]) * (i + 0.5) / FAN;
        FmRay r = {{x, info.bounds_min[1] - 1.0, z}, {0.0, 1.0, 0.0}, 0.0, 1e30, (uint64_t)i};
        rays[i] = r;
    }
    float *radiance = malloc(FAN * c * sizeof(float)), *transmittance = malloc(FAN * c * sizeof(float));
    FmRayQuery q = {.struct_size = sizeof q};
    q.what = FM_QUERY_INTEGRATE;
    q.n = FAN;
    q.rays = rays;
    q.radiance = radiance;
    q.transmittance = transmittance;
    check(api->volume_query(fire, &q), "volume_query");
    double brightest = 0.0;
    for (int i = 0; i < FAN; i++) {
        double y = 0.0;
        for (size_t k = 0; k < c; k++) y += radiance[i * c + k] * xyz[3 * k + 1];
        if (y > brightest) brightest = y;
        printf("ray x = %+.3f: Y %.4e cd/m^2, transmittance %.3f (middle channel)\n", rays[i].origin[0], y,
               transmittance[i * c + c / 2]);
    }

    /* The fire light: 256 points by the fire's power (6 uniform numbers each), and the light at a point beside
     * the fire: the radiance along each sampled direction over that direction's density, averaged. */
    FmLight *light = NULL;
    check(api->light_create(fire, NULL, 0, &light), "light_create");
    FmLightInfo linfo = {.struct_size = sizeof linfo};
    check(api->light_info(light, &linfo), "light_info");
    printf("fire light: %.4e W, %.4e lm over %llu voxels\n", linfo.power_w, linfo.power_lm,
           (unsigned long long)linfo.voxels);
    enum { N = 256 };
    double u[6 * N], points[3 * N], pdf[N], origins[3 * N], dirs[3 * N], pd[N];
    uint64_t state = 0x2545f4914f6cdd1dull;
    for (int i = 0; i < 6 * N; i++) u[i] = uniform(&state);
    check(api->light_sample(light, u, NULL, N, points, pdf, NULL), "light_sample");
    double at[3] = {info.bounds_max[0] + 1.0, 0.5 * (info.bounds_min[1] + info.bounds_max[1]),
                    0.5 * (info.bounds_min[2] + info.bounds_max[2])};
    FmRay shots[N];
    for (int i = 0; i < N; i++) {
        for (int a = 0; a < 3; a++) {
            origins[3 * i + a] = at[a];
            dirs[3 * i + a] = points[3 * i + a] - at[a];
        }
        FmRay r = {{at[0], at[1], at[2]}, {dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]}, 0.0, 1e30, 1000u + i};
        shots[i] = r;
    }
    check(api->light_pdf_direction(light, origins, dirs, NULL, N, pd), "light_pdf_direction");
    float *l = malloc(N * c * sizeof(float));
    /* The fire's emission along each direction as the light estimates it (a march whose steps do not grow with
     * the grid). */
    check(api->light_integrate(light, shots, NULL, N, l, NULL), "light_integrate");
    double sum = 0.0;
    for (int i = 0; i < N; i++) {
        if (!(pd[i] > 0.0)) continue;
        double y = 0.0;
        for (size_t k = 0; k < c; k++) y += l[i * c + k] * xyz[3 * k + 1];
        sum += y / pd[i];
    }
    printf("brightest %.6e\nscalar_illuminance %.6e\n", brightest, sum / N);

    free(l);
    free(radiance);
    free(transmittance);
    free(xyz);
    api->light_destroy(light);
    api->volume_destroy(fire);
    return 0;
}
