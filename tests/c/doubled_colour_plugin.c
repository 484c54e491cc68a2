/* A plugin that forwards every call to a real firemedium plugin (the file FIREMEDIUM_REAL_PLUGIN names) but
 * reports each channel's XYZ weights doubled: a host that takes its colour from the plugin it loaded renders
 * exactly twice as bright through it; one that computes its own weights renders the same. */
#include <dlfcn.h>
#include <stdlib.h>
#include "firemedium.h"

static FmApi table;
static const FmApi *real;

static FmStatus doubled_xyz(const FmVolume *volume, double *out, size_t cap) {
    FmStatus s = real->volume_channel_xyz(volume, out, cap);
    if (s == FM_OK && out) {
        for (size_t i = 0; i < cap; i++) out[i] *= 2.0;
    }
    return s;
}

const FmApi *firemedium_plugin_entry(void) {
    if (!real) {
        const char *path = getenv("FIREMEDIUM_REAL_PLUGIN");
        void *lib = path ? dlopen(path, RTLD_NOW | RTLD_LOCAL) : NULL;
        if (!lib) return NULL;
        const FmApi *(*entry)(void);
        *(void **)&entry = dlsym(lib, FIREMEDIUM_ENTRY_SYMBOL);
        if (!entry) return NULL;
        real = entry();
        if (!real) return NULL;
        table = *real;
        table.volume_channel_xyz = doubled_xyz;
    }
    return &table;
}
