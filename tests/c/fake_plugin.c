/* A library that claims to be a firemedium plugin of another ABI (99.0 unless FAKE_MAJOR and FAKE_MINOR say
 * otherwise, e.g. a 0.13 plugin from before 1.0): the loader must refuse it, naming both versions. */
#include "firemedium.h"
#ifndef FAKE_MAJOR
#define FAKE_MAJOR 99u
#define FAKE_MINOR 0u
#endif
static FmApi table = {FAKE_MAJOR, FAKE_MINOR, sizeof(FmApi), 0u};
const FmApi *firemedium_plugin_entry(void) { return &table; }
