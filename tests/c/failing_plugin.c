/* A plugin that forwards every call to a real firemedium plugin (the file FIREMEDIUM_REAL_PLUGIN names) but refuses
 * one whole-ray query in five (those of rays whose seed is a multiple of 5), as a plugin that hits an error in the
 * middle of a render would: the renderer must count and report such failures, never render them as silent black. */
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include "firemedium.h"

static FmApi table;
static const FmApi *real;
static const char MESSAGE[] = "failing shim: this query is refused (a test)";
static _Thread_local int refused;

static FmStatus refusing_query(const FmVolume *volume, const FmRayQuery *query) {
    if (query && query->n > 0 && query->rays && query->rays[0].seed % 5 == 0) {
        refused = 1;
        return FM_INVALID_ARGUMENT;
    }
    refused = 0;
    return real->volume_query(volume, query);
}

static size_t last_error(char *buf, size_t cap) {
    if (!refused) return real->last_error(buf, cap);
    size_t n = strlen(MESSAGE);
    if (buf && cap > 0) {
        size_t m = n < cap - 1 ? n : cap - 1;
        memcpy(buf, MESSAGE, m);
        buf[m] = 0;
    }
    return n;
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
        table.volume_query = refusing_query;
        table.last_error = last_error;
    }
    return &table;
}
