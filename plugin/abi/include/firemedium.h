/*
 * firemedium.h — the C ABI of the firemedium plugin (a physically based fire medium for path tracers).
 *
 * Hand-written to match the Rust crate firemedium-abi (plugin/abi/src/lib.rs); tests/c_header.rs compiles a C
 * program against this header, checks every struct size against the Rust layout, loads the built plugin and
 * renders a ray through it.
 *
 * Usage: dlopen the plugin, dlsym FIREMEDIUM_ENTRY_SYMBOL, call it, check abi_major == FM_ABI_MAJOR and
 * abi_minor >= FM_ABI_MINOR and struct_size >= sizeof(FmApi), then use the table. Every call returns an FmStatus;
 * on failure last_error() gives the message. Volumes are immutable and safe to query from many threads.
 * Batch outputs hold n * channels floats, channel fastest. Rays are in the medium's space. Each entry of FmApi
 * below says which arrays it reads and writes, their layout, and which outputs may be NULL;
 * plugin/abi/examples/fire_pixel.c is a complete host written from this header alone.
 */
#ifndef FIREMEDIUM_H
#define FIREMEDIUM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FM_ABI_MAJOR 0u
#define FM_ABI_MINOR 13u
#define FIREMEDIUM_ENTRY_SYMBOL "firemedium_plugin_entry"

typedef int32_t FmStatus;
#define FM_OK 0
#define FM_INVALID_ARGUMENT 1
#define FM_INVALID_PARAMETER 2
#define FM_DATASET 3
#define FM_UNSUPPORTED 4
#define FM_PANIC 5

#define FM_TYPE_FLOAT 0u    /* values: double[count] */
#define FM_TYPE_INTEGER 1u  /* int64_t[count] */
#define FM_TYPE_BOOL 2u     /* uint8_t[count] */
#define FM_TYPE_STRING 3u   /* const char*[count], UTF-8 */
#define FM_TYPE_POINT3 4u   /* double[count] */
#define FM_TYPE_VECTOR3 5u  /* double[count] */
#define FM_TYPE_RGB 6u      /* double[count] */
#define FM_TYPE_SPECTRUM 7u /* double[count]: one constant or (lambda nm, value) pairs */

typedef struct FmParam {
    const char *name;
    uint32_t ty;
    uint32_t count;
    const void *values;
} FmParam;

typedef struct FmRay {
    double origin[3];
    double direction[3];
    double tmin, tmax;
    uint64_t seed;
} FmRay;

typedef struct FmExit {
    double point[3];
    double direction[3];
    double t;
} FmExit;

#define FM_EVENT_ESCAPED 0u
#define FM_EVENT_SCATTERED 1u
#define FM_EVENT_ABSORBED 2u

typedef struct FmScatter {
    uint32_t event;
    uint32_t reserved;
    double t;
    double point[3];
} FmScatter;

#define FM_SPACE_SPECTRAL 0u /* channels are bins, W m^-2 sr^-1 nm^-1 */
#define FM_SPACE_XYZ 1u      /* channels are CIE XYZ, Y in cd/m^2 */

#define FM_INTEGRATOR_MARCH 0u
#define FM_INTEGRATOR_RATIO 1u
#define FM_INTEGRATOR_DELTA 2u

typedef struct FmVolumeInfo {
    double bounds_min[3];
    double bounds_max[3];
    uint32_t channels;
    uint32_t channel_space;
    double lambda_min, lambda_max;
    double g;
    uint32_t scatters;
    uint32_t integrator;
    double step;
    uint64_t bytes;
    double build_seconds;
} FmVolumeInfo;

/* ABI 0.11: volume_features bits. A host that tracks the medium itself (volume_coefficients at points, the
 * majorant grid for free paths) refuses, or keeps to the whole-ray queries for, what it cannot handle. */
#define FM_FEATURE_EMITS (1ull << 0)
#define FM_FEATURE_SCATTERS (1ull << 1)
#define FM_FEATURE_MOTION (1ull << 2)      /* point coefficients depend on time */
#define FM_FEATURE_REFRACTION (1ull << 3)  /* rays bend: lost by straight tracking */
#define FM_FEATURE_EMBERS (1ull << 4)      /* opaque spheres: only the whole-ray queries see them */
#define FM_FEATURE_THICK_LINES (1ull << 5) /* lines across their profiles: only the whole-ray queries */
#define FM_FEATURE_DIFFUSION (1ull << 6)   /* multiple scattering read as emission: only the whole-ray queries */
#define FM_FEATURE_EMITS_WITHOUT_ABSORPTION (1ull << 7) /* an emission grid: Le = j / sigma_a undefined where sigma_a = 0 */

/* ABI 0.11: the majorant grid, for a host's own free-path sampling: cells of cell[] medium units tiling the box
 * bounds[0..3] .. bounds[3..6] (the last per axis may be cut by the box), counts[] of them, and per cell (x
 * fastest) a bound on sigma_t (medium units^-1) over every channel and every point of the cell, over the shutter
 * with motion blur. A point of the volume's bounds outside the cells' box (pbrt mode's half-voxel margin) takes
 * the nearest cell's bound. sigma_t is owned by the volume and valid while it lives. The host sets struct_size
 * to sizeof(FmMajorantGrid) before the call. */
typedef struct FmMajorantGrid {
    size_t struct_size;
    double bounds[6];
    double cell[3];
    uint32_t counts[3];
    uint32_t reserved;
    const double *sigma_t;
} FmMajorantGrid;

/* ABI 0.11: a point query (volume_point): at n points, each at its time and at k wavelengths of its own, sigma_a,
 * sigma_s, the emitted radiance Le and the emission coefficient j = sigma_a Le -- the closed forms at each
 * wavelength (soot's kappa(lambda) and Planck's B(lambda, T); pbrt-v4's spectra and peak-normalised blackbody),
 * not the bins. Outputs are n*k doubles each, point-major, each may be NULL; Le is 0 where sigma_a is 0 (an
 * emission grid's j still emits there). A volume whose layers the closed forms cannot express (atomic lines, art
 * direction, a scatter colour grid, diffusion, refraction, embers) is refused with FM_UNSUPPORTED naming it. */
typedef struct FmPointQuery {
    size_t struct_size;    /* sizeof(FmPointQuery) */
    size_t n;              /* points */
    const double *points;  /* 3n, medium space (required) */
    const double *times;   /* n frames from the grids' time, or NULL: time 0 */
    uint32_t k;            /* wavelengths per point */
    uint32_t reserved;
    const double *lambdas; /* n*k nm (required) */
    double *sigma_a, *sigma_s, *le, *j;
} FmPointQuery;

/* ABI 0.12: the last error's structure (last_error_detail), beside its message: what a host needs to point its
 * user at the cause without parsing text. Strings are owned by the plugin, valid until the next call on the same
 * thread; NULL when the error has no such part. */
typedef struct FmErrorDetail {
    size_t struct_size;    /* sizeof(FmErrorDetail), set by the host */
    FmStatus status;       /* the failing call's status (FM_OK when none has failed on this thread) */
    int32_t reserved;
    const char *parameter; /* the parameter at fault, as the host named it */
    const char *location;  /* where the host said it was given (volume_create_located): file:line:col */
    const char *file;      /* the file whose reading or content failed */
    const char *position;  /* where in it: "byte 1234", "line 3, column 5", "grid 'density'" */
} FmErrorDetail;

/* ABI 0.13: a volume's creation (volume_create_with): the scene's parameters with their locations, and the host's
 * context beside them instead of as made-up parameters. A parameter the scene gives itself (threads, maxbytes, frame,
 * shutteropen, shutterclose) wins over the context. */
#define FM_CREATE_FRAME (1u << 0)   /* frame is set */
#define FM_CREATE_SHUTTER (1u << 1) /* shutter is set */
typedef struct FmCreateInfo {
    size_t struct_size;            /* sizeof(FmCreateInfo) */
    const FmParam *params;         /* may be NULL when count is 0 */
    const char *const *locations;  /* per parameter file:line:col or NULL; the array may be NULL */
    size_t count;
    uint32_t threads;              /* 0: the plugin's default (the machine's) */
    uint32_t flags;                /* FM_CREATE_* */
    uint64_t max_bytes;            /* 0: the plugin's default */
    int64_t frame;                 /* the frame a #### in a file name takes */
    double shutter[2];             /* the camera's shutter, frames from the grids' time */
} FmCreateInfo;

typedef struct FmParamInfo {
    const char *component, *name, *ty, *default_value, *unit, *range, *doc;
} FmParamInfo;

typedef void FmVolume;
typedef void FmLight;

#define FM_WEIGHTING_LUMINANCE 0u
#define FM_WEIGHTING_POWER 1u
#define FM_WEIGHTING_ESCAPING 2u /* ABI 0.8: power times the share that leaves the fire */

typedef struct FmLightInfo {
    double power_w;  /* whole spectrum, W */
    double power_lm; /* over the bins, lm */
    uint64_t voxels;
    uint64_t bytes;
    double build_seconds;
    uint32_t weighting;
    uint32_t line_block; /* ABI 0.9: voxels per side of the blocks its line estimate marches through (1: the
                          * fire's own voxels; "lineblock"); 0 from an older plugin */
} FmLightInfo;

/*
 * The function table. Conventions for every entry:
 * - Returns FM_OK or an error status; last_error() then holds the message (per thread).
 * - Batches: n entries; a ray is one FmRay; a point, origin or direction is 3 doubles (x, y, z) in the medium's
 *   space; per-channel outputs are n * channels floats, entry-major and channel fastest (out[i * channels + c]);
 *   channels comes from volume_info. Every input number is checked finite; a NaN is an error, not a result.
 * - "required" outputs must not be NULL (FM_INVALID_ARGUMENT); "may be NULL" outputs are skipped when NULL.
 * - Handles are immutable once created: call any entry on one handle from many threads at once.
 */
typedef struct FmApi {
    uint32_t abi_major, abi_minor, struct_size, reserved;
    /* The calling thread's last error message, UTF-8, NUL-terminated and truncated to cap bytes, into buf (may
     * be NULL to ask for the length); returns its full length in bytes without the NUL. */
    size_t (*last_error)(char *buf, size_t cap);
    /* Rows of the parameter tables of all components (dataset, volume, light): param_info(index) for each, index
     * < param_count(). A row's strings are static. The volume's parameters a host needs first: "dataset" (or
     * "filename": an OpenVDB/NanoVDB file), "densitygrid" and "temperaturegrid" (grid names; defaults "density",
     * "temperature"), "fuel" (propane, acetylene, ...), "stepsize" (voxels), "bins"/"lambdamin"/"lambdamax" or
     * "colormode" "rgb", "maxbytes" (the memory budget) — all in docs/params.md. */
    size_t (*param_count)(void);
    FmStatus (*param_info)(size_t index, FmParamInfo *out /* required */);
    /* A fire volume from count parameters (params may be NULL when count is 0); *out (required) receives the
     * handle. An unknown or unused parameter is an error naming it. */
    FmStatus (*volume_create)(const FmParam *params, size_t count, FmVolume **out);
    /* Destroys a volume (NULL is ignored). Lights made from it keep it alive until they are destroyed. */
    void (*volume_destroy)(FmVolume *volume);
    FmStatus (*volume_info)(const FmVolume *volume, FmVolumeInfo *out /* required */);
    /* 3 * channels doubles into out (cap: how many doubles out holds): the X, Y, Z of unit radiance in channel c
     * at out[3c], out[3c + 1], out[3c + 2] — a host's film turns channel radiance into XYZ with them. */
    FmStatus (*volume_channel_xyz)(const FmVolume *volume, double *out, size_t cap);
    /* Emission and absorption along n rays: radiance (required, n * channels floats), transmittance (may be
     * NULL, n * channels), exits (may be NULL, n: where each ray leaves — bent by refraction, or stopped by an
     * ember). */
    FmStatus (*volume_integrate)(const FmVolume *volume, const FmRay *rays, size_t n, float *radiance,
                                 float *transmittance, FmExit *exits);
    /* Transmittance only (shadow rays): transmittance required, n * channels floats. */
    FmStatus (*volume_transmittance)(const FmVolume *volume, const FmRay *rays, size_t n, float *transmittance);
    /* The first real scattering event per ray: events (required, n), weights (required, n * channels: the
     * throughput to multiply by what is scattered in at the event, or the transmittance if it escaped), emitted
     * (may be NULL, n * channels: the emission collected before the event). */
    FmStatus (*volume_sample_scatter)(const FmVolume *volume, const FmRay *rays, size_t n, FmScatter *events,
                                      float *weights, float *emitted);
    /* sigma_a, sigma_s (m^-1) and the emission coefficient j = sigma_a Le per channel at n points (3n doubles);
     * each output n * channels floats, each may be NULL. */
    FmStatus (*volume_coefficients)(const FmVolume *volume, const double *points, size_t n, float *sigma_a,
                                    float *sigma_s, float *emission);
    /* ABI 0.2: the fire light. light_create's parameters: "string weighting" "power" (default) or "luminance"
     * (params may be NULL when count is 0); *out required. The light keeps its volume alive. */
    FmStatus (*light_create)(const FmVolume *volume, const FmParam *params, size_t count, FmLight **out);
    void (*light_destroy)(FmLight *light);
    FmStatus (*light_info)(const FmLight *light, FmLightInfo *out /* required */);
    /* n points sampled by the fire's power: u holds 6 uniform numbers in [0, 1) per sample (6n doubles: the first
     * picks the voxel or ember, the last three place the point in it); points (required, 3n doubles), pdf
     * (required, n: density per unit medium volume), emission (may be NULL, n * channels: j at the point). */
    FmStatus (*light_sample)(const FmLight *light, const double *u, size_t n, double *points, double *pdf, float *emission);
    /* Density per unit medium volume of n points (3n doubles); pdf required, n doubles. */
    FmStatus (*light_pdf)(const FmLight *light, const double *points, size_t n, double *pdf);
    /* Solid-angle density with which light_sample's point lies in each direction from each origin (3n doubles
     * each; directions need not be unit): the integral of pdf(o + s d) s^2 ds. pdf required, n doubles. A host
     * estimates the fire's light at o by the radiance volume_integrate returns along the sampled direction over
     * this density (and weighs it against its BSDF sampling with it, by MIS). */
    FmStatus (*light_pdf_direction)(const FmLight *light, const double *origins, const double *directions, size_t n,
                                    double *pdf);
    /* ABI 0.3: lowest and highest temperature (K) of the volume into out[0], out[1] (required, 2 doubles; 0, 0
       without a temperature grid). */
    FmStatus (*volume_temperature_range)(const FmVolume *volume, double *out);
    /* ABI 0.4: volume_create with where each parameter came from: locations holds count NUL-terminated
     * strings ("file:line:col"; an entry may be NULL, and locations itself may be NULL). An error about a
     * parameter then begins with its location. */
    FmStatus (*volume_create_located)(const FmParam *params, const char *const *locations, size_t count,
                                      FmVolume **out);
    /* ABI 0.4: how many rays' tracking stopped at the per-ray collision cap so far, into *out (required; each cut
     * short as if absorbed: a bias towards dark a host should report). */
    FmStatus (*volume_capped_rays)(const FmVolume *volume, uint64_t *out);
    /* ABI 0.5: volume_integrate, volume_transmittance and volume_sample_scatter with a time per ray: times
     * holds n doubles (frames from the grids' time, inside the volume's shutteropen..shutterclose) or is NULL
     * (every ray at time 0). A volume with motion blur (a velocitygrid and an open shutter) is looked up where
     * its velocity carried it from, x - v(x) * velocityscale / fps * time, and its embers are where their
     * velocities carried them; any other volume ignores times. Outputs as the entries without times. */
    FmStatus (*volume_integrate_at)(const FmVolume *volume, const FmRay *rays, const double *times, size_t n,
                                    float *radiance, float *transmittance, FmExit *exits);
    FmStatus (*volume_transmittance_at)(const FmVolume *volume, const FmRay *rays, const double *times, size_t n,
                                        float *transmittance);
    FmStatus (*volume_sample_scatter_at)(const FmVolume *volume, const FmRay *rays, const double *times,
                                         size_t n, FmScatter *events, float *weights, float *emitted);
    /* ABI 0.6: the temperature (K) whose blackbody a viewer adapts to for this volume, into *out (required): its
     * hottest temperature when its colour is the physics' (Planck emission), 0 when its colour is art-directed (a
     * tint, or a colorramp short of physical 1: meant to be seen against a D65 white) or it has no temperature
     * grid. */
    FmStatus (*volume_white_temperature)(const FmVolume *volume, double *out);
    /* ABI 0.7: light_sample, light_pdf and light_pdf_direction with a time per entry: times holds n doubles
     * (frames from the grids' time) or is NULL (time 0). A volume's embers move while the shutter is open; the
     * light samples them where they are at that time, and the densities are those of a sample drawn then. u
     * holds 6 doubles per sample, points 3 per sample, origins and directions 3 per entry; emission (n *
     * channels floats, may be NULL) is the volume's j at the point (an ember is a surface: its light reaches a
     * host through volume_integrate_at along the sampled direction). */
    FmStatus (*light_sample_at)(const FmLight *light, const double *u, const double *times, size_t n,
                                double *points, double *pdf, float *emission);
    FmStatus (*light_pdf_at)(const FmLight *light, const double *points, const double *times, size_t n,
                             double *pdf);
    FmStatus (*light_pdf_direction_at)(const FmLight *light, const double *origins, const double *directions,
                                       const double *times, size_t n, double *pdf);
    /* ABI 0.8: the fire's emitted radiance and transmittance along n straight rays as the light estimates them
     * for next-event estimation along a sampled direction: radiance (required) and transmittance (may be NULL)
     * hold n * channels floats, times as light_sample_at. The volume's march at the light's "linestep" (coarser
     * than the volume's own on a large fire: its cost does not grow with the grid), corrected toward the
     * volume's own march with probability "linecorrection". Where its step is the volume's, the same as
     * volume_integrate_at without exits. */
    FmStatus (*light_integrate_at)(const FmLight *light, const FmRay *rays, const double *times, size_t n,
                                   float *radiance, float *transmittance);
    /* ABI 0.10: how many of the volume's channels the light's line estimate marches, into *out (required): the
     * volume's channel count, or fewer ("linechannels": a soot fire's spectral bins, the others following from
     * them). */
    FmStatus (*light_line_channels)(const FmLight *light, uint32_t *out);
    /* ABI 0.11: the medium level, first part. volume_features: FM_FEATURE_* bits into *out (required);
     * volume_majorant_grid: the majorant grid into *out (required, its struct_size set by the host). */
    FmStatus (*volume_features)(const FmVolume *volume, uint64_t *out);
    FmStatus (*volume_majorant_grid)(const FmVolume *volume, FmMajorantGrid *out);
    /* ABI 0.11: the point query (FmPointQuery above; query required). */
    FmStatus (*volume_point)(const FmVolume *volume, const FmPointQuery *query);
    /* ABI 0.12: the last error on this thread as a structure into *out (required, its struct_size set). */
    FmStatus (*last_error_detail)(FmErrorDetail *out);
    /* ABI 0.13: a volume from a creation info (info and out required). */
    FmStatus (*volume_create_with)(const FmCreateInfo *info, FmVolume **out);
} FmApi;

typedef const FmApi *(*FmEntry)(void);

#ifdef __cplusplus
}
#endif
#endif /* FIREMEDIUM_H */
