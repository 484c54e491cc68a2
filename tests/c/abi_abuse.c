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
    FmCreateInfo ok = {.struct_size = sizeof ok, .params = ok_params, .count = 5};
    FmVolume *vol = NULL;
    if (api->volume_create(&ok, &vol) != FM_OK) { fprintf(stderr, "valid volume refused\n"); return 1; }
    FmLight *light = NULL;
    if (api->light_create(vol, NULL, 0, &light) != FM_OK) { fprintf(stderr, "valid light refused\n"); return 1; }

    FmVolume *out = NULL;
    FmParamInfo info = {.struct_size = sizeof info};
    FmVolumeInfo vinfo = {.struct_size = sizeof vinfo};
    FmLightInfo linfo = {.struct_size = sizeof linfo};
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
    /* Each bad parameter list through a creation info of its own. */
    FmCreateInfo bad = ok;
    expect_failure("volume_create(null out)", api->volume_create(&ok, NULL));
    expect_failure("volume_create(null info)", api->volume_create(NULL, &out));
    bad.params = NULL;
    bad.count = 3;
    expect_failure("volume_create(null list)", api->volume_create(&bad, &out));
    bad.params = ok_params;
    bad.count = SIZE_MAX;
    expect_failure("volume_create(absurd count)", api->volume_create(&bad, &out));
    bad.count = 1;
    bad.params = &bad_type;
    expect_failure("volume_create(unknown type)", api->volume_create(&bad, &out));
    bad.params = &null_name;
    expect_failure("volume_create(null name)", api->volume_create(&bad, &out));
    bad.params = &null_values;
    expect_failure("volume_create(null values)", api->volume_create(&bad, &out));
    bad.params = &null_str;
    expect_failure("volume_create(null string)", api->volume_create(&bad, &out));
    bad = ok;
    bad.flags = FM_CREATE_SHUTTER;
    bad.shutter[0] = 1.0;
    expect_failure("volume_create(shutter closing before it opens)", api->volume_create(&bad, &out));
    bad = ok;
    bad.struct_size = 8;
    expect_failure("volume_create(unsized)", api->volume_create(&bad, &out));
    bad = ok;
    bad.directory = "scenes/\xff\xfe";
    expect_failure("volume_create(a folder that is not UTF-8)", api->volume_create(&bad, &out));
    FmParamInfo small_info = {.struct_size = 4};
    expect_failure("param_info(unsized)", api->param_info(0, &small_info));
    expect_failure("volume_info(null volume)", api->volume_info(NULL, &vinfo));
    expect_failure("volume_info(null out)", api->volume_info(vol, NULL));
    expect_failure("volume_channel_xyz(null out)", api->volume_channel_xyz(vol, NULL, 90));
    expect_failure("volume_channel_xyz(short)", api->volume_channel_xyz(vol, x, 2));
    {
        /* The whole-ray query: one valid query, each field made wrong in turn. */
        FmRay good = {{-1, 0.5, 0.5}, {1, 0, 0}, 0, 5, 1};
        FmRayQuery q0 = {.struct_size = sizeof q0, .what = FM_QUERY_INTEGRATE, .n = 1, .rays = &good};
        q0.radiance = f;
        FmRayQuery q = q0;
        expect_failure("volume_query(null volume)", api->volume_query(NULL, &q));
        expect_failure("volume_query(null query)", api->volume_query(vol, NULL));
        q.struct_size = 8;
        expect_failure("volume_query(unsized)", api->volume_query(vol, &q));
        q = q0;
        q.rays = NULL;
        q.n = 4;
        expect_failure("volume_query(null rays)", api->volume_query(vol, &q));
        q = q0;
        q.radiance = NULL;
        expect_failure("volume_query(null radiance)", api->volume_query(vol, &q));
        q = q0;
        q.rays = &nan_ray;
        expect_failure("volume_query(NaN ray)", api->volume_query(vol, &q));
        q = q0;
        q.n = SIZE_MAX;
        expect_failure("volume_query(absurd n)", api->volume_query(vol, &q));
        q = q0;
        q.what = 7;
        expect_failure("volume_query(unknown what)", api->volume_query(vol, &q));
        double u_one[1] = {1.0}, nan_one[1] = {NAN};
        q = q0;
        q.u = u_one;
        expect_failure("volume_query(u of 1)", api->volume_query(vol, &q));
        q = q0;
        q.times = nan_one;
        expect_failure("volume_query(NaN time)", api->volume_query(vol, &q));
        q = q0;
        q.step = -1.0;
        expect_failure("volume_query(negative step)", api->volume_query(vol, &q));
        FmExit exits[1];
        q = q0;
        q.step = 1.0;
        q.exits = exits;
        expect_failure("volume_query(step with exits)", api->volume_query(vol, &q));
        q = q0;
        q.what = FM_QUERY_TRANSMITTANCE;
        expect_failure("volume_query(transmittance, null out)", api->volume_query(vol, &q));
        q.transmittance = f;
        expect_failure("volume_query(transmittance, radiance set)", api->volume_query(vol, &q));
        q = q0;
        q.what = FM_QUERY_SCATTER;
        q.radiance = NULL;
        q.weights = f;
        expect_failure("volume_query(scatter, null events)", api->volume_query(vol, &q));
    }
    expect_failure("volume_coefficients(null points)", api->volume_coefficients(vol, NULL, 3, f, NULL, NULL));
    expect_failure("volume_coefficients(absurd n)", api->volume_coefficients(vol, x, SIZE_MAX / 2, NULL, NULL, NULL));
    x[0] = NAN;
    expect_failure("volume_coefficients(NaN point)", api->volume_coefficients(vol, x, 1, f, NULL, NULL));
    expect_failure("volume_fields(null points)", api->volume_fields(vol, NULL, 3, f));
    expect_failure("volume_fields(null out)", api->volume_fields(vol, x, 1, NULL));
    expect_failure("volume_fields(absurd n)", api->volume_fields(vol, x, SIZE_MAX / 2, f));
    expect_failure("volume_fields(NaN point)", api->volume_fields(vol, x, 1, f));
    expect_failure("volume_fields(null volume)", api->volume_fields(NULL, x, 1, f));
    {
        /* (1.3) The bricks: no count pointer, no volume, a buffer too small, and a NULL buffer claiming room. */
        size_t n = 0;
        int64_t one[3];
        expect_failure("volume_bricks(null count)", api->volume_bricks(vol, one, 1, NULL));
        expect_failure("volume_bricks(null volume)", api->volume_bricks(NULL, one, 1, &n));
        if (api->volume_bricks(vol, NULL, 0, &n) != FM_OK || n == 0) {
            fprintf(stderr, "volume_bricks(count only): status or count wrong (%zu)\n", n);
            return 1;
        }
        expect_failure("volume_bricks(cap below the count)", api->volume_bricks(vol, one, n - 1, &n));
        expect_failure("volume_bricks(null out with room)", api->volume_bricks(vol, NULL, n, &n));
    }
    {
        FmTables small_tables = {.struct_size = 8};
        expect_failure("volume_tables(null out)", api->volume_tables(vol, NULL));
        expect_failure("volume_tables(unsized)", api->volume_tables(vol, &small_tables));
        expect_failure("volume_tables(null volume)", api->volume_tables(NULL, &small_tables));
    }
    expect_failure("volume_temperature_range(null out)", api->volume_temperature_range(vol, NULL));
    expect_failure("volume_capped_rays(null out)", api->volume_capped_rays(vol, NULL));
    expect_failure("volume_capped_rays(null volume)", api->volume_capped_rays(NULL, &u64));
    expect_failure("light_create(null volume)", api->light_create(NULL, NULL, 0, (FmLight **)&out));
    expect_failure("light_create(null out)", api->light_create(vol, NULL, 0, NULL));
    expect_failure("light_info(null light)", api->light_info(NULL, &linfo));
    expect_failure("light_sample(NaN u)", api->light_sample(light, nan_u, NULL, 1, x, x + 3, NULL));
    expect_failure("light_sample(null points)", api->light_sample(light, nan_u, NULL, 1, NULL, x, NULL));
    expect_failure("light_sample(absurd n)", api->light_sample(light, nan_u, NULL, SIZE_MAX / 2, x, x, NULL));
    expect_failure("light_pdf(null light)", api->light_pdf(NULL, x, NULL, 1, x));
    expect_failure("light_pdf(NaN point)", api->light_pdf(light, x, NULL, 1, x + 8));
    expect_failure("light_pdf_direction(null pdf)", api->light_pdf_direction(light, x, x, NULL, 1, NULL));
    {
        double good_u[6] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5}, nan_time[1] = {NAN}, dir[3] = {1, 0, 0}, o3[3] = {-1, 0, 0};
        expect_failure("light_sample(NaN time)", api->light_sample(light, good_u, nan_time, 1, x, x + 3, NULL));
        expect_failure("light_pdf(null light, times)", api->light_pdf(NULL, o3, NULL, 1, x));
        expect_failure("light_pdf_direction(NaN time)", api->light_pdf_direction(light, o3, dir, nan_time, 1, x));
        expect_failure("light_pdf_direction(null pdf, times)", api->light_pdf_direction(light, o3, dir, NULL, 1, NULL));
        expect_failure("light_integrate(null light)", api->light_integrate(NULL, &nan_ray, NULL, 1, f, NULL));
        expect_failure("light_integrate(null radiance)", api->light_integrate(light, &nan_ray, NULL, 1, NULL, NULL));
        expect_failure("light_integrate(NaN ray)", api->light_integrate(light, &nan_ray, NULL, 1, f, f));
        expect_failure("light_integrate(NaN time)", api->light_integrate(light, &nan_ray, nan_time, 1, f, NULL));
        expect_failure("light_integrate(absurd n)", api->light_integrate(light, &nan_ray, NULL, SIZE_MAX, f, NULL));
        FmLightInfo small_light = {.struct_size = 4};
        expect_failure("light_info(unsized)", api->light_info(light, &small_light));
        FmVolumeInfo small_volume = {.struct_size = 4};
        expect_failure("volume_info(unsized)", api->volume_info(vol, &small_volume));
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
    }
    api->volume_destroy(NULL);
    api->light_destroy(NULL);

    /* Still working afterwards. */
    FmRay ray = {{-1, 0.5, 0.5}, {1, 0, 0}, 0, 5, 1};
    FmRayQuery q = {.struct_size = sizeof q, .what = FM_QUERY_INTEGRATE, .n = 1, .rays = &ray};
    q.radiance = f;
    FmStatus s = api->volume_query(vol, &q);
    printf("afterwards %d\n", s);
    if (s != FM_OK || !(f[15] > 0)) { fprintf(stderr, "the plugin stopped working\n"); failures++; }
    api->light_destroy(light);
    api->volume_destroy(vol);
    printf("failures %d\n", failures);
    return failures ? 1 : 0;
}
