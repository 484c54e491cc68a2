/*
 * firemedium.h — the C ABI of the firemedium plugin (a physically based fire medium for path tracers).
 *
 * Hand-written to match the Rust crate firemedium-abi (plugin/abi/src/lib.rs); tests/abi/c_header.rs compiles a C
 * program against this header, checks every struct size against the Rust layout, loads the built plugin and
 * renders a ray through it.
 *
 * Usage: dlopen the plugin, dlsym FIREMEDIUM_ENTRY_SYMBOL, call it, check fm_api_compatible() (abi_major ==
 * FM_ABI_MAJOR, abi_minor >= FM_ABI_MINOR, struct_size >= sizeof(FmApi)), then use the table. Structs with a
 * struct_size are best initialised designated, {.struct_size = sizeof x}: the rest is zero. Every call returns an FmStatus;
 * on failure last_error() gives the message. Volumes are immutable and safe to query from many threads.
 * Batch outputs hold n * channels floats, channel fastest. Rays are in the medium's space. Every struct that
 * crosses the boundary begins with struct_size, which the host sets to sizeof the struct it was built with (array
 * elements -- FmParam, FmRay, FmExit, FmScatter -- have the layout of the major version); a struct grows only at
 * its end between minor versions, and the plugin reads only the fields a host's struct_size covers, the newer
 * ones taking their defaults, so a host built against an older 1.x header keeps working. A host asks a medium
 * the two questions pbrt-v4 and Mitsuba 3 ask (volume_point: the coefficients at a point, at the host's
 * wavelengths and time; volume_majorant_grid: a bound on sigma_t), or hands it whole rays (volume_query, the fast
 * path). Each entry of FmApi below says which arrays it reads and writes, their layout, and which outputs may be
 * NULL;
 * plugin/abi/examples/fire_pixel.c is a complete host written from this header alone.
 */
#ifndef FIREMEDIUM_H
#define FIREMEDIUM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FM_ABI_MAJOR 1u
#define FM_ABI_MINOR 4u
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
    size_t struct_size; /* sizeof(FmVolumeInfo), set by the host */
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
    /* (1.2) The dataset's lattice: samples per axis, cell-centred over lattice_min..lattice_max (medium space) --
     * where a host that bakes or samples the fire's grids asks for them (volume_coefficients). A 1.0/1.1 host's
     * smaller struct gets the fields it knows. */
    uint32_t dims[3];
    uint32_t reserved;
    double lattice_min[3];
    double lattice_max[3];
} FmVolumeInfo;

/* volume_features bits. A host that tracks the medium itself (volume_point at points, the majorant grid for
 * free paths) refuses, or keeps to the whole-ray queries for, what it cannot handle. */
#define FM_FEATURE_EMITS (1ull << 0)
#define FM_FEATURE_SCATTERS (1ull << 1)
#define FM_FEATURE_MOTION (1ull << 2)      /* point coefficients depend on time */
#define FM_FEATURE_REFRACTION (1ull << 3)  /* rays bend: lost by straight tracking */
#define FM_FEATURE_EMBERS (1ull << 4)      /* opaque spheres: only the whole-ray queries see them */
#define FM_FEATURE_THICK_LINES (1ull << 5) /* lines across their profiles: only the whole-ray queries */
#define FM_FEATURE_DIFFUSION (1ull << 6)   /* multiple scattering read as emission: only the whole-ray queries */
#define FM_FEATURE_EMITS_WITHOUT_ABSORPTION (1ull << 7) /* an emission grid: Le = j / sigma_a undefined where sigma_a = 0 */

/* The majorant grid, for a host's own free-path sampling: cells of cell[] medium units tiling the box
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

/* A point query (volume_point): at n points, each at its time and at k wavelengths of its own, sigma_a,
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

/* (1.2) The volume's coefficients in closed form (volume_tables), for a host that textures the fire rather than
 * asking for points. With d, T and les the fields (volume_fields) interpolated trilinearly from the lattice's voxel
 * values (a zero layer around the lattice; nothing outside the volume's bounds), d and les clamped at 0,
 * r = clamp(T / dt, 0, rows - 1) and the tables linear between rows:
 *   sigma_a = d * A(r), sigma_s = d * S, j = e * J(r) where T > t_emit (else 0),
 *   e = les with FM_TABLES_EMISSION_GRID, d * les without
 * in the volume's channels, per medium unit: what volume_coefficients gives at every point. The host sets
 * struct_size and the three table pointers (each may be NULL: a first call learns channels and rows); the plugin
 * writes the rest. */
typedef struct FmTables {
    size_t struct_size;   /* sizeof(FmTables) */
    uint32_t channels;
    uint32_t rows;        /* of the temperature tables */
    uint32_t flags;       /* FM_TABLES_* */
    uint32_t reserved;
    double dt;            /* K between rows: row r holds T = r * dt */
    double t_emit;        /* emits where T > t_emit (pbrt mode's 100 K; 0 physical; -inf without temperature) */
    float *absorption;    /* host's rows * channels floats (row-major), or NULL: sigma_a per unit density */
    float *scattering;    /* host's channels floats, or NULL: sigma_s per unit density */
    float *emission;      /* host's rows * channels floats, or NULL: j per unit of e */
} FmTables;
#define FM_TABLES_EMISSION_GRID 1u /* e = les (an emission grid), not d * les */

/* The last error's structure (last_error_detail), beside its message: what a host needs to point its
 * user at the cause without parsing text. Strings are owned by the plugin, valid until the next call on the same
 * thread; NULL when the error has no such part. */
typedef struct FmErrorDetail {
    size_t struct_size;    /* sizeof(FmErrorDetail), set by the host */
    FmStatus status;       /* the failing call's status (FM_OK when none has failed on this thread) */
    int32_t reserved;
    const char *parameter; /* the parameter at fault, as the host named it */
    const char *location;  /* where the host said it was given (FmCreateInfo.locations): file:line:col */
    const char *file;      /* the file whose reading or content failed */
    const char *position;  /* where in it: "byte 1234", "line 3, column 5", "grid 'density'" */
    int64_t index;         /* 1.4: the parameter at fault as its index in the failing call's list (FmCreateInfo.params
                            * or light_create's params; a look's parameter: the look's), or -1 when none the host
                            * passed. A host that keeps its own places for its parameters finds the place here and
                            * may pass no locations: the message then begins with no place of the plugin's making. */
} FmErrorDetail;
/* The size FmErrorDetail had in ABI 1.0 to 1.3, before index: the least a host may pass (the plugin writes as much
 * as struct_size covers). */
#define FM_ERROR_DETAIL_SIZE_1_0 48u

/* A volume's creation (volume_create): the scene's parameters with their locations, and the host's
 * context beside them (threads, memory budget, frame, shutter, the kind of medium the scene named, the render's
 * spectral bins) instead of as made-up parameters. A parameter the scene gives itself (threads, maxbytes, frame,
 * shutteropen, shutterclose, mode, bins, lambdamin, lambdamax) wins over the context. */
/* A part of the plugin's build work: task(data, index); it never unwinds into the host. */
typedef void (*FmTask)(void *data, size_t index);
/* A host's thread pool: runs task(data, i) for every i in 0..count -- on its threads as it likes, in any order, the
 * calling thread included -- and returns when every one has returned. */
typedef void (*FmParallelFor)(void *pool, size_t count, FmTask task, void *data);
#define FM_CREATE_FRAME (1u << 0)   /* frame is set */
#define FM_CREATE_SHUTTER (1u << 1) /* shutter is set */
#define FM_KIND_SCENE 0u /* kind: the scene's "mode" parameter, else the paper's fire */
#define FM_KIND_FIRE 1u  /* kind: the paper's fire (mode "physical") */
#define FM_KIND_PBRT 2u  /* kind: pbrt-v4's uniformgrid and nanovdb (mode "pbrt") */
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
    FmParallelFor parallel_for;    /* the host's thread pool, or NULL: the plugin's builds (this volume's and its
                                    * lights') run their parallel parts as its tasks instead of starting threads of
                                    * their own ("threads" still bounds how many parts a fan-out cuts). It must stay
                                    * callable while the volume and its lights live. */
    void *pool;                    /* handed back to parallel_for */
    const char *directory;         /* the folder relative file names are in (a scene's), or NULL: the working
                                    * directory; the plugin resolves its own file parameters against it */
    uint32_t kind;                 /* 1.4: FM_KIND_* (0: the scene's "mode", else the paper's fire) */
    uint32_t bins;                 /* 1.4: the render's spectral bins (0: the scene's "bins", else the default) */
    double wavelengths[2];         /* 1.4: the bins' span, nm (both 0: the scene's lambdamin/lambdamax, else the
                                    * defaults) */
} FmCreateInfo;

typedef struct FmParamInfo {
    size_t struct_size; /* sizeof(FmParamInfo), set by the host */
    const char *component, *name, *ty, *default_value, *unit, *range, *doc;
} FmParamInfo;

typedef void FmVolume;
typedef void FmLight;

#define FM_WEIGHTING_LUMINANCE 0u
#define FM_WEIGHTING_POWER 1u
#define FM_WEIGHTING_ESCAPING 2u /* power times the share that leaves the fire */

typedef struct FmLightInfo {
    size_t struct_size; /* sizeof(FmLightInfo), set by the host */
    double power_w;  /* whole spectrum, W (soot, atoms; the blue core whole; over the bins for an emission grid, tint or ramp) */
    double power_lm; /* over the bins, lm */
    uint64_t voxels;
    uint64_t bytes;
    double build_seconds;
    uint32_t weighting;
    uint32_t line_block; /* voxels per side of the blocks its line estimate marches through (1: the fire's own
                          * voxels; "lineblock") */
} FmLightInfo;

/* The fast whole-ray query (volume_query): n rays, each at its time, integrated, attenuated or tracked to a
 * scattering event by the plugin. Outputs are n * channels floats (channel fastest) or n entries; those the query
 * does not write must be NULL. */
#define FM_QUERY_INTEGRATE 0u     /* radiance (required), transmittance, exits (may be NULL) */
#define FM_QUERY_TRANSMITTANCE 1u /* transmittance (required): shadow rays */
#define FM_QUERY_SCATTER 2u       /* events, weights (required), radiance (may be NULL): the emission before the event */
typedef struct FmRayQuery {
    size_t struct_size;   /* sizeof(FmRayQuery) */
    uint32_t what;        /* FM_QUERY_* */
    uint32_t reserved;
    size_t n;
    const FmRay *rays;    /* n (required when n > 0) */
    const double *times;  /* n frames from the grids' time (inside the volume's shutter), or NULL: time 0. A volume
                           * with motion blur is looked up where its velocity carried it from, x - v(x) *
                           * velocityscale / fps * time; its embers are where theirs carried them. */
    const double *u;      /* n uniform numbers in [0, 1), or NULL: the first random number each ray's estimator
                           * draws (the march's offset, tracking's first free flight) -- the host's own sample,
                           * stratified as its sampler is; the rest come from the ray's seed */
    double step;          /* FM_QUERY_INTEGRATE without exits: the march's step, medium units, when longer than the
                           * volume's own (a coarse estimate); 0: the volume's. Tracking volumes ignore it. */
    float *radiance;      /* n * channels: emitted radiance (for a scatter query: before the event) */
    float *transmittance; /* n * channels */
    FmExit *exits;        /* n: where each ray leaves (bent by refraction, stopped by an ember); without exits the
                           * ray stays straight, as next-event estimation and light paths want */
    FmScatter *events;    /* n */
    float *weights;       /* n * channels: the throughput to multiply by what is scattered in at the event, or the
                           * transmittance if the ray escaped */
} FmRayQuery;

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
    /* The last error on this thread as a structure into *out (required, its struct_size set). */
    FmStatus (*last_error_detail)(FmErrorDetail *out);
    /* Rows of the parameter tables of all components (dataset, volume, light): param_info(index) for each, index
     * < param_count(). A row's strings are static. The volume's parameters a host needs first: "dataset" (or
     * "filename": an OpenVDB/NanoVDB file), "densitygrid" and "temperaturegrid" (grid names; defaults "density",
     * "temperature"), "fuel" (propane, acetylene, ...), "stepsize" (voxels), "bins"/"lambdamin"/"lambdamax" or
     * "colormode" "rgb", "maxbytes" (the memory budget) — all in docs/reference/params.md. */
    size_t (*param_count)(void);
    FmStatus (*param_info)(size_t index, FmParamInfo *out /* required, struct_size set */);
    /* A fire volume from a creation info (FmCreateInfo above; required); *out (required) receives the handle. An
     * unknown or unused parameter is an error naming it (and its location, when given). */
    FmStatus (*volume_create)(const FmCreateInfo *info, FmVolume **out);
    /* Destroys a volume (NULL is ignored). Lights made from it keep it alive until they are destroyed. */
    void (*volume_destroy)(FmVolume *volume);
    FmStatus (*volume_info)(const FmVolume *volume, FmVolumeInfo *out /* required, struct_size set */);
    /* 3 * channels doubles into out (cap: how many doubles out holds): the X, Y, Z of unit radiance in channel c
     * at out[3c], out[3c + 1], out[3c + 2] — a host's film turns channel radiance into XYZ with them. */
    FmStatus (*volume_channel_xyz)(const FmVolume *volume, double *out, size_t cap);
    /* Lowest and highest temperature (K) of the volume into out[0], out[1] (required, 2 doubles; 0, 0 without a
       temperature grid). */
    FmStatus (*volume_temperature_range)(const FmVolume *volume, double *out);
    /* The temperature (K) whose blackbody a viewer adapts to for this volume, into *out (required): its hottest
     * temperature when its colour is the physics' (Planck emission), 0 when its colour is art-directed (a tint, or
     * a colorramp short of physical 1: meant to be seen against a D65 white) or it has no temperature grid. */
    FmStatus (*volume_white_temperature)(const FmVolume *volume, double *out);
    /* How many rays' tracking stopped at the per-ray collision cap so far, into *out (required; each cut short as
     * if absorbed: a bias towards dark a host should report). */
    FmStatus (*volume_capped_rays)(const FmVolume *volume, uint64_t *out);
    /* The fast path: whole rays (FmRayQuery above; query required). */
    FmStatus (*volume_query)(const FmVolume *volume, const FmRayQuery *query);
    /* The medium level. volume_features: FM_FEATURE_* bits into *out (required); volume_majorant_grid: the majorant
     * grid into *out (required, its struct_size set); volume_point: the point query (FmPointQuery above; query
     * required). */
    FmStatus (*volume_features)(const FmVolume *volume, uint64_t *out);
    FmStatus (*volume_majorant_grid)(const FmVolume *volume, FmMajorantGrid *out);
    FmStatus (*volume_point)(const FmVolume *volume, const FmPointQuery *query);
    /* sigma_a, sigma_s (m^-1) and the emission coefficient j = sigma_a Le in the volume's own channels at n points
     * (3n doubles; every layer, lines and art direction included, at time 0); each output n * channels floats,
     * each may be NULL. */
    FmStatus (*volume_coefficients)(const FmVolume *volume, const double *points, size_t n, float *sigma_a,
                                    float *sigma_s, float *emission);
    /* The fire light. light_create's parameters: "string weighting" "power" (default), "luminance" or "escaping",
     * and the rest of the light table (params may be NULL when count is 0); *out required. The light keeps its
     * volume alive. */
    FmStatus (*light_create)(const FmVolume *volume, const FmParam *params, size_t count, FmLight **out);
    void (*light_destroy)(FmLight *light);
    FmStatus (*light_info)(const FmLight *light, FmLightInfo *out /* required, struct_size set */);
    /* n points sampled by the fire's power, each at its time (times: n doubles, frames from the grids' time, or
     * NULL: time 0; a volume's embers move while the shutter is open and are sampled where they are then): u holds
     * 6 uniform numbers in [0, 1) per sample (6n doubles: the first picks the voxel or ember, the last three place
     * the point in it); points (required, 3n doubles), pdf (required, n: density per unit medium volume), emission
     * (may be NULL, n * channels: j at the point; an ember is a surface: its light reaches a host through
     * volume_query along the sampled direction). */
    FmStatus (*light_sample)(const FmLight *light, const double *u, const double *times, size_t n, double *points,
                             double *pdf, float *emission);
    /* Density per unit medium volume of n points (3n doubles) of a sample drawn at each time (as light_sample);
     * pdf required, n doubles. */
    FmStatus (*light_pdf)(const FmLight *light, const double *points, const double *times, size_t n, double *pdf);
    /* Solid-angle density with which light_sample's point lies in each direction from each origin (3n doubles
     * each; directions need not be unit), for a sample drawn at each time: the integral of pdf(o + s d) s^2 ds.
     * pdf required, n doubles. A host estimates the fire's light at o by the radiance light_integrate returns along
     * the sampled direction over this density (and weighs it against its BSDF sampling with it, by MIS). */
    FmStatus (*light_pdf_direction)(const FmLight *light, const double *origins, const double *directions,
                                    const double *times, size_t n, double *pdf);
    /* The fire's emitted radiance and transmittance along n straight rays as the light estimates them for
     * next-event estimation along a sampled direction: radiance (required) and transmittance (may be NULL) hold
     * n * channels floats, times as light_sample. The volume's march at the light's "linestep" (coarser than the
     * volume's own on a large fire: its cost does not grow with the grid), corrected toward the volume's own
     * march with probability "linecorrection". Where its step is the volume's, the same as volume_query without
     * exits. */
    FmStatus (*light_integrate)(const FmLight *light, const FmRay *rays, const double *times, size_t n,
                                float *radiance, float *transmittance);
    /* How many of the volume's channels the light's line estimate marches, into *out (required): the volume's
     * channel count, or fewer ("linechannels": a soot fire's spectral bins, the others following from them). */
    FmStatus (*light_line_channels)(const FmLight *light, uint32_t *out);
    /* (1.1) How many notes the volume's build left, into *out (required): what a user should hear whatever host
     * renders it — species whose lines fall outside the channels, flame colours the model cannot give. */
    FmStatus (*volume_note_count)(const FmVolume *volume, size_t *out);
    /* (1.1) Note index (< the count), UTF-8, NUL-terminated and truncated to cap bytes, into buf (may be NULL to
     * ask for the length); its full length in bytes without the NUL into *len (required). */
    FmStatus (*volume_note)(const FmVolume *volume, size_t index, char *buf, size_t cap, size_t *len);
    /* (1.2) The volume's coefficients in closed form into *out (required, its struct_size and table pointers set;
     * FmTables above); FM_UNSUPPORTED naming what is not of that form (atomic lines, a scatter colour grid,
     * diffusion, refraction, embers, motion blur, a dataset not interpolated trilinearly). */
    FmStatus (*volume_tables)(const FmVolume *volume, FmTables *out);
    /* (1.2) The closed form's fields at n medium-space points (3n doubles) into out (3n floats, point-major): soot
     * density d, temperature T (K) and the Lescale or emission grid's value les (1 without one), as the volume
     * interpolates them; zeros outside. At the lattice's voxel centres, the voxels' own values: what a host
     * textures. */
    FmStatus (*volume_fields)(const FmVolume *volume, const double *points, size_t n, float *out);
    /* (1.3) The bricks of 8^3 samples the volume's grids store -- what its dataset holds, not its box: two fires far
     * apart are bricks of their own -- in the lattice's sample indices (FmVolumeInfo.dims): per brick the index
     * (i, j, k) of its first sample, 3 int64_t each, in no set order. An index may be below 0 (a sparse
     * file's leaves stay whole where the lattice starts inside one); samples outside 0..dims are not the fire's.
     * Their count into *count (required); out may be NULL with cap 0 to ask for it alone; a cap below the count is
     * FM_INVALID_ARGUMENT, nothing written. What a host that bakes or textures the fire sparsely asks for, rather
     * than reading the dataset again. */
    FmStatus (*volume_bricks)(const FmVolume *volume, int64_t *out, size_t cap, size_t *count);
} FmApi;

typedef const FmApi *(*FmEntry)(void);

/* 1 when a plugin's table suits a host built with this header: the same major version, a minor at least this
 * header's, a table at least this header's FmApi. (Written so that a minor of 0 compiles without warnings.) */
static inline int fm_api_compatible(const FmApi *api) {
    return api != NULL && api->abi_major == FM_ABI_MAJOR && (uint64_t)api->abi_minor + 1u > (uint64_t)FM_ABI_MINOR &&
           api->struct_size >= sizeof(FmApi);
}

#ifdef __cplusplus
}
#endif
#endif /* FIREMEDIUM_H */
