/*
 * Loading a shared library, the one platform-specific part of the C
 * importers (importer.c, importer3.c): dlopen on Linux, LoadLibrary on Windows.
 */
#ifndef CONVERTING_SPAN_LIBRARY_H
#define CONVERTING_SPAN_LIBRARY_H

#include <stdio.h>


#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *path) { return LoadLibraryA(path); }
static void *find_symbol(Library lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static void close_library(Library lib) { FreeLibrary(lib); }
static const char *library_error(void)
{
    static char text[64];
    snprintf(text, sizeof text, "Windows error %lu", (unsigned long)GetLastError());
    return text;
}
#else
#include <dlfcn.h>
typedef void *Library;
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *find_symbol(Library lib, const char *name) { return dlsym(lib, name); }
static void close_library(Library lib) { dlclose(lib); }
static const char *library_error(void) { return dlerror(); }
#endif

#endif
