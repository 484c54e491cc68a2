/* Every entry of the table called with bad arguments: null handles, null buffers, absurd counts, NaN numbers,
 * unknown type codes. Each must return a failure status other than FM_PANIC (which means a plugin bug) and leave
 * a message, and the plugin must go on working. Prints one line per call: "entry status"; exits 0 when every
 * call behaved, 1 naming the first that did not. Usage: abi_abuse PLUGIN */
#include <dlfcn.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "firemedium.h"

static const FmApi *api;
static int failures;

static void expect_failure(const char *what, FmStatus s) {
    char msg[256];
    size_t n = api->last_error(msg, sizeof msg);
    printf("%s %d\n", what, s);
    if (s == FM_OK || s == FM_PANIC || n == 0) {
        fprintf(stderr, "%s: status %d, message '%s'\n", what, s, n ? msg : "");
        failures++;
    }
}

int main(int argc, char **argv) {
    if (argc != 2) return 2;
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 2; }
    const FmApi *(*entry)(void);
    *(void **)&entry = dlsym(lib, FIREMEDIUM_ENTRY_SYMBOL);
    api = entry();

    /* A small valid volume and light to abuse the queries with. */
    double d[8] = {1, 1, 1, 1, 1, 1, 1, 1}, t[8] = {1500, 1500, 1500, 1500, 1500, 1500, 1500, 1500};
    int64_t two = 2;
    FmParam ok_params[5] = {{"density", FM_TYPE_FLOAT, 8, d}, {"temperature", FM_TYPE_FLOAT, 8, t},
                            {"nx", FM_TYPE_INTEGER, 1, &two}, {"ny", FM_TYPE_INTEGER, 1, &two},
                            {"nz", FM_TYPE_INTEGER, 1, &two}};
    FmVolume *vol = NULL;
    if (api->volume_create(ok_params, 5, &vol) != FM_OK) { fprintf(stderr, "valid volume refused\n"); return 1; }
    FmLight *light = NULL;
    if (api->light_create(vol, NULL, 0, &light) != FM_OK) { fprintf(stderr, "valid light refused\n"); return 1; }

    FmVolume *out = NULL;
    FmParamInfo info;
    FmVolumeInfo vinfo;
    FmLightInfo linfo;
    float f[64];
    double x[64];
    uint64_t u64;
    FmRay nan_ray = {{NAN, 0, 0}, {1, 0, 0}, 0, 1, 1};
    FmParam bad_type = {"density", 99u, 8, d};
    FmParam null_name = {NULL, FM_TYPE_FLOAT, 8, d};
    FmParam null_values = {"density", FM_TYPE_FLOAT, 8, NULL};
    const char *null_string = NULL;
    FmParam null_str = {"filename", FM_TYPE_STRING, 1, &null_string};
    double nan_u[6] = {0.5, NAN, 0.5, 0.5, 0.5, 0.5};

    expect_failure("param_info(out of range)", api->param_info(SIZE_MAX, &info));
    expect_failure("param_info(null out)", api->param_info(0, NULL));
    expect_failure("volume_create(null out)", api->volume_create(ok_params, 5, NULL));
    expect_failure("volume_create(null list)", api->volume_create(NULL, 3, &out));
    expect_failure("volume_create(absurd count)", api->volume_create(ok_params, SIZE_MAX, &out));
    expect_failure("volume_create(unknown type)", api->volume_create(&bad_type, 1, &out));
    expect_failure("volume_create(null name)", api->volume_create(&null_name, 1, &out));
    expect_failure("volume_create(null values)", api->volume_create(&null_values, 1, &out));
    expect_failure("volume_create(null string)", api->volume_create(&null_str, 1, &out));
    expect_failure("volume_create_located(null list)", api->volume_create_located(NULL, NULL, 2, &out));
    expect_failure("volume_info(null volume)", api->volume_info(NULL, &vinfo));
    expect_failure("volume_info(null out)", api->volume_info(vol, NULL));
    expect_failure("volume_channel_xyz(null out)", api->volume_channel_xyz(vol, NULL, 90));
    expect_failure("volume_channel_xyz(short)", api->volume_channel_xyz(vol, x, 2));
    expect_failure("volume_integrate(null volume)", api->volume_integrate(NULL, &nan_ray, 1, f, NULL, NULL));
    expect_failure("volume_integrate(null rays)", api->volume_integrate(vol, NULL, 4, f, NULL, NULL));
    expect_failure("volume_integrate(null radiance)", api->volume_integrate(vol, &nan_ray, 1, NULL, NULL, NULL));
    expect_failure("volume_integrate(NaN ray)", api->volume_integrate(vol, &nan_ray, 1, f, NULL, NULL));
    expect_failure("volume_integrate(absurd n)", api->volume_integrate(vol, &nan_ray, SIZE_MAX, f, NULL, NULL));
    expect_failure("volume_transmittance(null out)", api->volume_transmittance(vol, &nan_ray, 1, NULL));
    expect_failure("volume_transmittance(NaN ray)", api->volume_transmittance(vol, &nan_ray, 1, f));
    expect_failure("volume_sample_scatter(null events)", api->volume_sample_scatter(vol, &nan_ray, 1, NULL, f, NULL));
    expect_failure("volume_coefficients(null points)", api->volume_coefficients(vol, NULL, 3, f, NULL, NULL));
    expect_failure("volume_coefficients(absurd n)", api->volume_coefficients(vol, x, SIZE_MAX / 2, NULL, NULL, NULL));
    x[0] = NAN;
    expect_failure("volume_coefficients(NaN point)", api->volume_coefficients(vol, x, 1, f, NULL, NULL));
    expect_failure("volume_temperature_range(null out)", api->volume_temperature_range(vol, NULL));
    expect_failure("volume_capped_rays(null out)", api->volume_capped_rays(vol, NULL));
    expect_failure("volume_capped_rays(null volume)", api->volume_capped_rays(NULL, &u64));
    expect_failure("light_create(null volume)", api->light_create(NULL, NULL, 0, (FmLight **)&out));
    expect_failure("light_create(null out)", api->light_create(vol, NULL, 0, NULL));
    expect_failure("light_info(null light)", api->light_info(NULL, &linfo));
    expect_failure("light_sample(NaN u)", api->light_sample(light, nan_u, 1, x, x + 3, NULL));
    expect_failure("light_sample(null points)", api->light_sample(light, nan_u, 1, NULL, x, NULL));
    expect_failure("light_sample(absurd n)", api->light_sample(light, nan_u, SIZE_MAX / 2, x, x, NULL));
    expect_failure("light_pdf(null light)", api->light_pdf(NULL, x, 1, x));
    expect_failure("light_pdf(NaN point)", api->light_pdf(light, x, 1, x + 8));
    expect_failure("light_pdf_direction(null pdf)", api->light_pdf_direction(light, x, x, 1, NULL));
    {
        double good_u[6] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5}, nan_time[1] = {NAN}, dir[3] = {1, 0, 0}, o3[3] = {-1, 0, 0};
        expect_failure("light_sample_at(NaN time)", api->light_sample_at(light, good_u, nan_time, 1, x, x + 3, NULL));
        expect_failure("light_pdf_at(null light)", api->light_pdf_at(NULL, o3, NULL, 1, x));
        expect_failure("light_pdf_direction_at(NaN time)", api->light_pdf_direction_at(light, o3, dir, nan_time, 1, x));
        expect_failure("light_pdf_direction_at(null pdf)", api->light_pdf_direction_at(light, o3, dir, NULL, 1, NULL));
        expect_failure("light_integrate_at(null light)", api->light_integrate_at(NULL, &nan_ray, NULL, 1, f, NULL));
        expect_failure("light_integrate_at(null radiance)", api->light_integrate_at(light, &nan_ray, NULL, 1, NULL, NULL));
        expect_failure("light_integrate_at(NaN ray)", api->light_integrate_at(light, &nan_ray, NULL, 1, f, f));
        expect_failure("light_integrate_at(NaN time)", api->light_integrate_at(light, &nan_ray, nan_time, 1, f, NULL));
        expect_failure("light_integrate_at(absurd n)", api->light_integrate_at(light, &nan_ray, NULL, SIZE_MAX, f, NULL));
        expect_failure("light_line_channels(null light)", api->light_line_channels(NULL, (uint32_t *)x));
        expect_failure("light_line_channels(null out)", api->light_line_channels(light, NULL));
        /* The medium level: null handles and outputs, a struct the host did not size, NaN and negative
         * wavelengths, absurd counts. */
        FmMajorantGrid grid;
        grid.struct_size = 8;
        expect_failure("volume_features(null volume)", api->volume_features(NULL, &u64));
        expect_failure("volume_features(null out)", api->volume_features(vol, NULL));
        expect_failure("volume_majorant_grid(null out)", api->volume_majorant_grid(vol, NULL));
        expect_failure("volume_majorant_grid(unsized)", api->volume_majorant_grid(vol, &grid));
        double pt[3] = {0.5, 0.5, 0.5}, lam[2] = {NAN, -500.0}, outs[2];
        FmPointQuery q = {sizeof q, 1, pt, NULL, 1, 0, lam, outs, NULL, NULL, NULL};
        expect_failure("volume_point(null query)", api->volume_point(vol, NULL));
        expect_failure("volume_point(NaN wavelength)", api->volume_point(vol, &q));
        q.lambdas = lam + 1;
        expect_failure("volume_point(negative wavelength)", api->volume_point(vol, &q));
        q.lambdas = NULL;
        expect_failure("volume_point(null wavelengths)", api->volume_point(vol, &q));
        q.lambdas = lam + 1;
        q.n = SIZE_MAX / 2;
        expect_failure("volume_point(absurd n)", api->volume_point(vol, &q));
        q.n = 1;
        q.struct_size = 8;
        expect_failure("volume_point(unsized)", api->volume_point(vol, &q));
        FmErrorDetail detail;
        detail.struct_size = 4;
        expect_failure("last_error_detail(null out)", api->last_error_detail(NULL));
        expect_failure("last_error_detail(unsized)", api->last_error_detail(&detail));
        FmCreateInfo ci = {sizeof ci, ok_params, NULL, 5, 0, FM_CREATE_SHUTTER, 0, 0, {1.0, 0.0}};
        expect_failure("volume_create_with(null info)", api->volume_create_with(NULL, &out));
        expect_failure("volume_create_with(null out)", api->volume_create_with(&ci, NULL));
        expect_failure("volume_create_with(shutter closing before it opens)", api->volume_create_with(&ci, &out));
        ci.struct_size = 8;
        expect_failure("volume_create_with(unsized)", api->volume_create_with(&ci, &out));
    }
    api->volume_destroy(NULL);
    api->light_destroy(NULL);

    /* Still working afterwards. */
    FmRay ray = {{-1, 0.5, 0.5}, {1, 0, 0}, 0, 5, 1};
    FmStatus s = api->volume_integrate(vol, &ray, 1, f, NULL, NULL);
    printf("afterwards %d\n", s);
    if (s != FM_OK || !(f[15] > 0)) { fprintf(stderr, "the plugin stopped working\n"); failures++; }
    api->light_destroy(light);
    api->volume_destroy(vol);
    printf("failures %d\n", failures);
    return failures ? 1 : 0;
}
