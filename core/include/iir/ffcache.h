/* ffcache.h -- the radiosity form factors' cache folder as a whole, for whoever reports on it or
 * configures it (iird's --cache-max and /metrics): where it is, its cap, what it holds. Not its
 * file format or its reader (core/src/radiosity/radiosity.h). Holds no state: the configuration is
 * the process's environment, read at each call ($IIR_CACHE_DIR, $IIR_CACHE_MAX). */
#ifndef IIR_FFCACHE_H
#define IIR_FFCACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The environment variable that caps the folder (bytes, or with K, M, G, T), read by every save;
 * `iird serve|render|bench --cache-max SIZE` sets it before any thread starts. */
#define IIR_FFCACHE_MAX_ENV "IIR_CACHE_MAX"

/* The folder (into dir, at most n bytes; "" when caching is off) and its cap in bytes. */
void iir_ffcache_config(char *dir, size_t n, uint64_t *max_bytes);

/* What dir holds: the bytes and number of its cache files (regular files named as the cache
 * names them). False (both 0) when dir cannot be read, e.g. before the first save made it. */
bool iir_ffcache_usage(const char *dir, uint64_t *bytes, uint64_t *files);

#ifdef __cplusplus
}
#endif
#endif
