/* Plugins that speak the right ABI version but cannot be used, one per BROKEN value: 1, the entry returns null;
 * 2, the table declares fewer bytes than its version has; 3, every function pointer is null. The loader must
 * refuse each, saying what is wrong, instead of crashing the host. */
#include <stddef.h>
#include "firemedium.h"

FmApi firemedium_broken_table = {FM_ABI_MAJOR, FM_ABI_MINOR, sizeof(FmApi), 0u};

const FmApi *firemedium_plugin_entry(void) {
#if BROKEN == 1
    return NULL;
#elif BROKEN == 2
    firemedium_broken_table.struct_size = 16u;
    return &firemedium_broken_table;
#else
    return &firemedium_broken_table;
#endif
}
