/*
 * The loader: the FMU's folder resolved, its modelDescription.xml read (FMI version,
 * modelIdentifier, guid or instantiationToken), its library of the host's platform opened
 * (dlopen, LoadLibrary) and the version's front bound. The one place of the host that
 * knows the operating system's library calls and the platform folders.
 */
#if !defined(_WIN32) && !defined(_XOPEN_SOURCE)
#define _XOPEN_SOURCE 700   /* realpath */
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#endif

#include "host.h"

FILE *host_log_stream;

#ifdef _WIN32
#define SEP "\\"
#else
#define SEP "/"
#endif

/* the binaries/ folder of this platform: FMI 2.0's names where the standard has one
   (linux64, win64, win32, darwin64), FMI 3.0's platform tuple elsewhere (aarch64 Linux, as
   FMI 2.0.5 says) */
const char *host_platform_folder(int version)
{
#if defined(_WIN32) && (defined(_M_X64) || defined(__x86_64__))
    return version == 2 ? "win64" : "x86_64-windows";
#elif defined(_WIN32)
    return version == 2 ? "win32" : "x86-windows";
#elif defined(__APPLE__) && defined(__aarch64__)
    return version == 2 ? "darwin64" : "aarch64-darwin";
#elif defined(__APPLE__)
    return version == 2 ? "darwin64" : "x86_64-darwin";
#elif defined(__aarch64__)
    (void)version;
    return "aarch64-linux";
#elif defined(__i386__)
    return version == 2 ? "linux32" : "x86-linux";
#else
    return version == 2 ? "linux64" : "x86_64-linux";
#endif
}

const char *host_library_suffix(void)
{
#if defined(_WIN32)
    return ".dll";
#elif defined(__APPLE__)
    return ".dylib";
#else
    return ".so";
#endif
}

void (*host_symbol(HostFmu *f, const char *name))(void)
{
    void (*fn)(void);
#ifdef _WIN32
    FARPROC p = GetProcAddress((HMODULE)f->library, name);
    memcpy(&fn, &p, sizeof fn);
#else
    void *p = dlsym(f->library, name);
    memcpy(&fn, &p, sizeof fn);
#endif
    return fn;
}

void host_log(const char *instance, int status, const char *category, const char *text)
{
    char line[8192];
    char *p;
    snprintf(line, sizeof line, "%s", text ? text : "(null)");
    for (p = line; *p; p++)
        if (*p == '\n') *p = ' ';
    fprintf(host_log_stream ? host_log_stream : stderr, "LOG %s %d %s %s\n",
            instance ? instance : "(null)", status, category ? category : "(null)", line);
}

static void resolve(HostFmu *f, const char *given)
{
#ifdef _WIN32
    if (!_fullpath(f->dir, given, sizeof f->dir)) {
#else
    if (!realpath(given, f->dir)) {
#endif
        fprintf(stderr, "no folder %s\n", given);
        exit(2);
    }
}

/* modelDescription.xml's text (NULL if the folder has none) */
static char *read_description(const char *dir)
{
    char path[4200];
    FILE *file;
    long size;
    char *text = NULL;
    snprintf(path, sizeof path, "%s/modelDescription.xml", dir);
    file = fopen(path, "rb");
    if (!file) return NULL;
    if (fseek(file, 0, SEEK_END) == 0 && (size = ftell(file)) >= 0
        && fseek(file, 0, SEEK_SET) == 0 && (text = (char *)malloc((size_t)size + 1))) {
        text[fread(text, 1, (size_t)size, file)] = '\0';
    }
    fclose(file);
    return text;
}

static void describe(HostFmu *f, const char *identifier, const char *token)
{
    char version[16] = "";
    f->description = read_description(f->dir);
    if (!f->description
        || !host_attribute(f->description, "fmiModelDescription", "fmiVersion", version,
                           sizeof version)) {
        fprintf(stderr, "%s/modelDescription.xml: no fmiVersion (2.0 or 3.0 accepted)\n",
                f->dir);
        exit(2);
    }
    f->version = version[0] == '2' ? 2 : version[0] == '3' ? 3 : 0;
    if (!f->version) {
        fprintf(stderr, "%s/modelDescription.xml: fmiVersion %s (2.0 or 3.0 accepted)\n",
                f->dir, version);
        exit(2);
    }
    if (identifier) snprintf(f->identifier, sizeof f->identifier, "%s", identifier);
    else host_attribute(f->description, "CoSimulation", "modelIdentifier", f->identifier,
                        sizeof f->identifier);
    if (token) snprintf(f->token, sizeof f->token, "%s", token);
    else host_attribute(f->description, "fmiModelDescription",
                        f->version == 2 ? "guid" : "instantiationToken", f->token,
                        sizeof f->token);
}

void host_load(HostFmu *f, const char *dir, const char *identifier, const char *token)
{
    char path[8192];
    resolve(f, dir);
    describe(f, identifier, token);
    snprintf(path, sizeof path, "%s%sbinaries%s%s%s%s%s", f->dir, SEP, SEP,
             host_platform_folder(f->version), SEP, f->identifier, host_library_suffix());
#ifdef _WIN32
    f->library = (void *)LoadLibraryA(path);
#else
    f->library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
#endif
    if (!f->library) {
        fprintf(stderr, "cannot load %s\n", path);
        exit(2);
    }
    if (f->version == 2) host_fmi2_bind(f);
    else host_fmi3_bind(f);
}
