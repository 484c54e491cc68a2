/* A C host: loads the firemedium plugin through firemedium.h, creates a fire volume and integrates one ray.
 * Usage: smoke PLUGIN.so DATASET.vdb   — prints "key value" lines for tests/c_header.rs. */
#include "firemedium.h"
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A host's thread pool, serial: runs every task on the calling thread and counts them. */
static size_t pool_tasks;
static void serial_pool(void *pool, size_t count, FmTask task, void *data) {
    (void)pool;
    for (size_t i = 0; i < count; i++) {
        pool_tasks++;
        task(data, i);
    }
}

int main(int argc, char **argv) {
    if (argc != 3) { fprintf(stderr, "usage: smoke PLUGIN DATASET\n"); return 2; }
    printf("header_abi %u.%u\n", FM_ABI_MAJOR, FM_ABI_MINOR);
    printf("sizeof_FmRay %zu\nsizeof_FmExit %zu\nsizeof_FmScatter %zu\nsizeof_FmVolumeInfo %zu\n",
           sizeof(FmRay), sizeof(FmExit), sizeof(FmScatter), sizeof(FmVolumeInfo));
    printf("sizeof_FmParam %zu\nsizeof_FmParamInfo %zu\nsizeof_FmApi %zu\nsizeof_FmLightInfo %zu\n", sizeof(FmParam), sizeof(FmParamInfo), sizeof(FmApi), sizeof(FmLightInfo));
    printf("sizeof_FmMajorantGrid %zu\nsizeof_FmPointQuery %zu\nsizeof_FmErrorDetail %zu\nsizeof_FmCreateInfo %zu\n",
           sizeof(FmMajorantGrid), sizeof(FmPointQuery), sizeof(FmErrorDetail), sizeof(FmCreateInfo));
    printf("sizeof_FmRayQuery %zu\nsizeof_FmTables %zu\n", sizeof(FmRayQuery), sizeof(FmTables));
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 1; }
    FmEntry entry = (FmEntry)dlsym(lib, FIREMEDIUM_ENTRY_SYMBOL);
    if (!entry) { fprintf(stderr, "no entry symbol\n"); return 1; }
    const FmApi *api = entry();
    printf("abi %u.%u\nstruct_size %u\n", api->abi_major, api->abi_minor, api->struct_size);
    if (!fm_api_compatible(api)) return 3;
    printf("param_count %zu\n", api->param_count());

    const char *file = argv[2];
    double tscale = 1000.0, soot = 1e-6;
    FmParam params[3] = {
        {"filename", FM_TYPE_STRING, 1, &file},
        {"temperaturescale", FM_TYPE_FLOAT, 1, &tscale},
        {"sootscale", FM_TYPE_FLOAT, 1, &soot},
    };
    FmCreateInfo create = {.struct_size = sizeof create, .params = params, .count = 3, .threads = 2,
                           .parallel_for = serial_pool};
    FmVolume *vol = NULL;
    if (api->volume_create(&create, &vol) != FM_OK) {
        char msg[512];
        api->last_error(msg, sizeof msg);
        fprintf(stderr, "volume_create: %s\n", msg);
        return 1;
    }
    FmVolumeInfo info = {.struct_size = sizeof info};
    api->volume_info(vol, &info);
    printf("channels %u\npool_tasks %zu\n", info.channels, pool_tasks);
    double trange[2] = {-1.0, -1.0};
    FmStatus ts = api->volume_temperature_range(vol, trange);
    printf("temperature_status %d\ntemperature_min %.9g\ntemperature_max %.9g\n", ts, trange[0], trange[1]);
    FmRay ray = {{1.0, -1.0, 0.5}, {0.0, 1.0, 0.0}, 0.0, 10.0, 7};
    float *radiance = calloc(info.channels, sizeof(float)), *transmittance = calloc(info.channels, sizeof(float));
    FmExit exit;
    FmRayQuery rq = {.struct_size = sizeof rq, .what = FM_QUERY_INTEGRATE, .n = 1, .rays = &ray};
    rq.radiance = radiance;
    rq.transmittance = transmittance;
    rq.exits = &exit;
    FmStatus s = api->volume_query(vol, &rq);
    printf("integrate_status %d\nradiance_29 %.9g\ntransmittance_29 %.9g\nexit_y %.9g\n", s, radiance[29], transmittance[29], exit.point[1]);
    /* The medium level: what the volume holds, and its majorant grid (the cell of the ray's start). */
    uint64_t features = 0;
    FmStatus fs = api->volume_features(vol, &features);
    FmMajorantGrid grid;
    grid.struct_size = sizeof grid;
    FmStatus gs = api->volume_majorant_grid(vol, &grid);
    printf("features_status %d\nfeatures %llu\nmajorant_status %d\nmajorant_cells %u %u %u\nmajorant_first %.9g\n", fs,
           (unsigned long long)features, gs, grid.counts[0], grid.counts[1], grid.counts[2], grid.sigma_t[0]);
    /* The point query at the ray's midpoint inside the fire, at two wavelengths. */
    double point[3] = {1.0, 1.0, 0.5}, lambdas[2] = {450.0, 650.0}, sa[2], le[2];
    FmPointQuery q = {sizeof q, 1, point, NULL, 2, 0, lambdas, sa, NULL, le, NULL};
    FmStatus ps = api->volume_point(vol, &q);
    printf("point_status %d\npoint_sigma_a_650 %.9g\npoint_le_650 %.9g\n", ps, sa[1], le[1]);
    /* The closed form (1.2): the tables' size first, then the tables; j at the point from its fields, against
     * volume_coefficients there. */
    FmTables tab = {.struct_size = sizeof tab};
    FmStatus t1 = api->volume_tables(vol, &tab);
    size_t cells = (size_t)tab.rows * tab.channels;
    tab.absorption = calloc(cells, sizeof(float));
    tab.emission = calloc(cells, sizeof(float));
    tab.scattering = calloc(tab.channels, sizeof(float));
    FmStatus t2 = api->volume_tables(vol, &tab);
    float fields[3], j_coef[64];
    FmStatus fl = api->volume_fields(vol, point, 1, fields);
    api->volume_coefficients(vol, point, 1, NULL, NULL, j_coef);
    double r = fields[1] / tab.dt;
    if (r > tab.rows - 1) r = tab.rows - 1;
    size_t i0 = (size_t)r < tab.rows - 2 ? (size_t)r : tab.rows - 2;
    double fr = r - (double)i0, e = (tab.flags & FM_TABLES_EMISSION_GRID) ? fields[2] : fields[0] * fields[2];
    double j29 = fields[1] > tab.t_emit
        ? e * (tab.emission[i0 * tab.channels + 29] * (1 - fr) + tab.emission[(i0 + 1) * tab.channels + 29] * fr)
        : 0.0;
    printf("tables_status %d %d %d\ntables_rows %u\nclosed_form_j29 %.9g\ncoefficients_j29 %.9g\n", t1, t2, fl, tab.rows,
           j29, j_coef[29]);
    free(tab.absorption);
    free(tab.emission);
    free(tab.scattering);
    /* The fire light: one sample, its pdf evaluated again. */
    FmLight *light = NULL;
    if (api->light_create(vol, NULL, 0, &light) != FM_OK) return 1;
    FmLightInfo linfo = {.struct_size = sizeof linfo};
    api->light_info(light, &linfo);
    double u[6] = {0.3, 0.6, 0.2, 0.5, 0.5, 0.5}, pt[3], pdf, pdf2;
    api->light_sample(light, u, NULL, 1, pt, &pdf, NULL);
    api->light_pdf(light, pt, NULL, 1, &pdf2);
    printf("light_power_w %.9g\nlight_voxels %llu\nlight_pdf %.9g\nlight_pdf_again %.9g\n", linfo.power_w, (unsigned long long)linfo.voxels, pdf, pdf2);
    api->light_destroy(light);
    /* A bad parameter comes back as a status and a message, not a crash. */
    FmParam bad[1] = {{"stepsise", FM_TYPE_FLOAT, 1, &tscale}};
    FmVolume *none = NULL;
    FmCreateInfo bad_create = {.struct_size = sizeof bad_create, .params = bad, .count = 1};
    FmStatus b = api->volume_create(&bad_create, &none);
    char msg[512];
    api->last_error(msg, sizeof msg);
    printf("bad_status %d\nbad_message %s\n", b, msg);
    FmErrorDetail detail;
    detail.struct_size = sizeof detail;
    FmStatus ds = api->last_error_detail(&detail);
    printf("detail_status %d %d\ndetail_parameter %s\ndetail_index %lld\n", ds, detail.status,
           detail.parameter ? detail.parameter : "(null)", (long long)detail.index);
    /* A host built against 1.0-1.3 passes the struct as it was then: the plugin writes that much. */
    uint64_t raw[8];
    unsigned char *old = (unsigned char *)raw;
    memset(old, 0xAB, sizeof raw);
    size_t old_size = FM_ERROR_DETAIL_SIZE_1_0;
    memcpy(old, &old_size, sizeof old_size);
    FmStatus os = api->last_error_detail((FmErrorDetail *)(void *)raw);
    int untouched = 1;
    for (size_t i = FM_ERROR_DETAIL_SIZE_1_0; i < sizeof raw; i++) untouched &= old[i] == 0xAB;
    printf("detail_1_0 %d %d\n", os, untouched);
    api->volume_destroy(vol);
    free(radiance);
    free(transmittance);
    return 0;
}
