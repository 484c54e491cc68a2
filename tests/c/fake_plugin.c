/* A library that claims to be a firemedium plugin of ABI 99.0: the loader must refuse it, naming both versions. */
#include "firemedium.h"
static FmApi table = {99u, 0u, sizeof(FmApi), 0u};
const FmApi *firemedium_plugin_entry(void) { return &table; }
