/*
 * Loading a shared library, the one platform-specific part of every C
 * program that loads an FMU's library (the importers, the hardening and
 * benchmark drivers): dlopen on Linux, LoadLibrary on Windows.
 */
#ifndef CONVERTING_SPAN_LIBRARY_H
#define CONVERTING_SPAN_LIBRARY_H

#include <stdio.h>
#include <string.h>


#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static inline Library open_library(const char *path) { return LoadLibraryA(path); }
static inline void *find_symbol(Library lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static inline void close_library(Library lib) { FreeLibrary(lib); }
/* Whether the library is still mapped into the process (a reference is left). */
static inline int library_is_loaded(const char *path)
{
    const char *name = strrchr(path, '\\') ? strrchr(path, '\\') + 1 : strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    return GetModuleHandleA(name) != NULL;
}
static inline const char *library_error(void)
{
    static char text[64];
    snprintf(text, sizeof text, "Windows error %lu", (unsigned long)GetLastError());
    return text;
}
#else
#include <dlfcn.h>
typedef void *Library;
static inline Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static inline void *find_symbol(Library lib, const char *name) { return dlsym(lib, name); }
static inline void close_library(Library lib) { dlclose(lib); }
/* Whether the library is still mapped into the process (a reference is left). */
static inline int library_is_loaded(const char *path)
{
    void *still = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (still != NULL) dlclose(still);
    return still != NULL;
}
static inline const char *library_error(void) { return dlerror(); }
#endif

#endif
