/* A plain C host of the FMU, run natively and under valgrind by
 * scripts/c_host_test.sh, and compiled with MinGW-w64 and run under wine
 * by scripts/windows_test.sh.
 *
 * Usage: host FMU_DIR [OUTPUTS.csv] (FMU_DIR an unpacked .fmu:
 * modelDescription.xml, binaries/<platform>/, resources/).
 *
 * It loads binaries/linux64/origami_fmu.so with dlopen, or on Windows
 * binaries/win64/origami_fmu.dll with LoadLibrary, reads the GUID and the
 * value references of the inputs and outputs from modelDescription.xml,
 * and drives one
 * co-simulation: setup, initialization, an input, steps (outputs finite),
 * FMU states (get/set/free and a serialize round trip, both reproducing a
 * step bit for bit; a flipped bit or a truncation refused), reset, a
 * second run, terminate and free (a state not freed by the host goes with
 * its instance). Between
 * those it calls with NULL, misaligned and foreign arguments and checks
 * that each gets fmi2Error (or NULL from fmi2Instantiate), not a crash.
 * With OUTPUTS.csv it then runs a fresh instance for 100 steps of 1 ms with
 * the first input ramped from 0 to 1 (slopes given) and writes the time and every output after each
 * step (%.17g, under a header of the names), to compare platforms. Exit status 0 when every check holds.
 *
 * The FMI 2.0 prototypes are declared here by hand (the standard's headers
 * are not vendored); only the functions used are looked up. */
#ifdef _WIN32
/* MinGW's C99 printf (%zu, %.17g as on Linux) rather than msvcrt's. */
#define __USE_MINGW_ANSI_STDIO 1
#include <windows.h>
#else
#define _GNU_SOURCE
#include <dlfcn.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The shared library calls, dlfcn's or the Windows API's. */
#ifdef _WIN32
typedef HMODULE library;
#define BINARY "\\binaries\\win64\\origami_fmu.dll"
static library open_library(const char *path) { return LoadLibraryA(path); }
static void *library_symbol(library lib, const char *name) {
    return (void *)GetProcAddress(lib, name);
}
static int close_library(library lib) { return FreeLibrary(lib) ? 0 : -1; }
static const char *library_error(void) {
    static char text[64];
    snprintf(text, sizeof text, "Windows error %lu", (unsigned long)GetLastError());
    return text;
}
static char *absolute_path(const char *path) { return _fullpath(NULL, path, 0); }
#else
typedef void *library;
#define BINARY "/binaries/linux64/origami_fmu.so"
static library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *library_symbol(library lib, const char *name) { return dlsym(lib, name); }
static int close_library(library lib) { return dlclose(lib); }
static const char *library_error(void) { return dlerror(); }
static char *absolute_path(const char *path) { return realpath(path, NULL); }
#endif

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
} fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

/* The functions used, looked up by name. */
static struct {
    fmi2String (*GetVersion)(void);
    fmi2String (*GetTypesPlatform)(void);
    fmi2Status (*SetDebugLogging)(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
    fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String,
                                 const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
    void (*FreeInstance)(fmi2Component);
    fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                                  fmi2Real);
    fmi2Status (*EnterInitializationMode)(fmi2Component);
    fmi2Status (*ExitInitializationMode)(fmi2Component);
    fmi2Status (*Terminate)(fmi2Component);
    fmi2Status (*Reset)(fmi2Component);
    fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
    fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
    fmi2Status (*GetInteger)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Integer[]);
    fmi2Status (*SetBoolean)(fmi2Component, const fmi2ValueReference[], size_t,
                             const fmi2Boolean[]);
    fmi2Status (*GetString)(fmi2Component, const fmi2ValueReference[], size_t, fmi2String[]);
    fmi2Status (*GetFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SetFMUstate)(fmi2Component, fmi2FMUstate);
    fmi2Status (*FreeFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SerializedFMUstateSize)(fmi2Component, fmi2FMUstate, size_t *);
    fmi2Status (*SerializeFMUstate)(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
    fmi2Status (*DeSerializeFMUstate)(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate *);
    fmi2Status (*SetRealInputDerivatives)(fmi2Component, const fmi2ValueReference[], size_t,
                                          const fmi2Integer[], const fmi2Real[]);
    fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    fmi2Status (*GetBooleanStatus)(fmi2Component, fmi2StatusKind, fmi2Boolean *);
    fmi2Status (*GetRealStatus)(fmi2Component, fmi2StatusKind, fmi2Real *);
    fmi2Status (*SetTime)(fmi2Component, fmi2Real);
} F;

static int checks, failures;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        checks++;                                                                    \
        if (!(cond)) {                                                               \
            failures++;                                                              \
            fprintf(stderr, "host.c:%d: check failed: %s\n", __LINE__, #cond);      \
        }                                                                            \
    } while (0)

/* Log lines per status, and the last message (for the checks that an
 * error says why). */
static int logged[6];
static char last_message[1024];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)category;
    va_list ap;
    va_start(ap, message);
    vsnprintf(last_message, sizeof last_message, message, ap);
    va_end(ap);
    if (status >= fmi2OK && status <= fmi2Pending) logged[status]++;
}

static void *sym(library lib, const char *name) {
    void *p = library_symbol(lib, name);
    if (!p) {
        fprintf(stderr, "host.c: %s not exported: %s\n", name, library_error());
        exit(2);
    }
    return p;
}

static char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
        fprintf(stderr, "host.c: cannot read %s\n", path);
        exit(2);
    }
    buf[n] = '\0';
    fclose(f);
    return buf;
}

/* The value of attribute `name` (e.g. `guid="`) in [p, end), copied into
 * out; 0 when absent. */
static int attribute(const char *p, const char *end, const char *name, char *out, size_t cap) {
    const char *a = strstr(p, name);
    if (!a || a >= end) return 0;
    a += strlen(name);
    const char *q = strchr(a, '"');
    if (!q || q >= end || (size_t)(q - a) >= cap) return 0;
    memcpy(out, a, (size_t)(q - a));
    out[q - a] = '\0';
    return 1;
}

#define MAX_VARS 4096
static fmi2ValueReference inputs[MAX_VARS], outputs[MAX_VARS];
static size_t n_inputs, n_outputs;
static char output_names[MAX_VARS][128];

/* The GUID, the value references of inputs and outputs, and the names of
 * the outputs. */
static void read_model_description(const char *xml, char *guid, size_t cap) {
    if (!attribute(xml, xml + strlen(xml), "guid=\"", guid, cap)) {
        fprintf(stderr, "host.c: no guid in modelDescription.xml\n");
        exit(2);
    }
    for (const char *p = strstr(xml, "<ScalarVariable "); p; p = strstr(p + 1, "<ScalarVariable ")) {
        /* Attribute values never hold '<' (escaped), so the element ends
         * before its closing tag. */
        const char *end = strstr(p, "</ScalarVariable>");
        char vr[32], causality[32], name[128];
        if (!end || !attribute(p, end, " valueReference=\"", vr, sizeof vr) ||
            !attribute(p, end, " causality=\"", causality, sizeof causality) ||
            !attribute(p, end, " name=\"", name, sizeof name)) {
            fprintf(stderr, "host.c: unreadable ScalarVariable\n");
            exit(2);
        }
        fmi2ValueReference r = (fmi2ValueReference)strtoul(vr, NULL, 10);
        if (!strcmp(causality, "input") && n_inputs < MAX_VARS) inputs[n_inputs++] = r;
        if (!strcmp(causality, "output") && n_outputs < MAX_VARS) {
            memcpy(output_names[n_outputs], name, sizeof name);
            outputs[n_outputs++] = r;
        }
    }
    if (n_inputs == 0 || n_outputs == 0) {
        fprintf(stderr, "host.c: the scene needs an input and outputs\n");
        exit(2);
    }
}

static const fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};

/* Outputs after `steps` steps of h from t: fmi2OK each, every value
 * finite. Returns the time reached. */
static double step_and_read(fmi2Component c, double t, double h, int steps, double *out) {
    for (int k = 0; k < steps; k++, t += h) CHECK(F.DoStep(c, t, h, fmi2True) == fmi2OK);
    CHECK(F.GetReal(c, outputs, n_outputs, out) == fmi2OK);
    int finite = 1;
    for (size_t i = 0; i < n_outputs; i++) finite &= isfinite(out[i]) != 0;
    CHECK(finite);
    return t;
}

static void initialize(fmi2Component c) {
    CHECK(F.SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(F.EnterInitializationMode(c) == fmi2OK);
    CHECK(F.ExitInitializationMode(c) == fmi2OK);
}

/* Calls that must fail cleanly on a handle that is not a live instance. */
static void bad_handle(fmi2Component c) {
    double v = 0.0;
    fmi2FMUstate s = NULL;
    CHECK(F.SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2Error);
    CHECK(F.DoStep(c, 0.0, 0.01, fmi2True) == fmi2Error);
    CHECK(F.GetReal(c, outputs, 1, &v) == fmi2Error);
    CHECK(F.GetFMUstate(c, &s) == fmi2Error && s == NULL);
    CHECK(F.Reset(c) == fmi2Error);
    F.FreeInstance(c); /* ignored */
}

/* A fresh instance: 100 steps of 1 ms, the first input ramped from 0 to 1
 * with its slope given (fmi2SetRealInputDerivatives), the time and every
 * output after each step written to csv_path. A smooth drive, so that the
 * trajectory is well conditioned: a held jump to 1 whips the sheet, and that
 * motion moves by several percent when the tolerance changes by 1e-7, so two
 * platforms' last bits would not compare the platforms. */
static void trajectory(const char *guid, const char *uri, const char *csv_path) {
    FILE *f = fopen(csv_path, "w");
    if (!f) {
        perror(csv_path);
        exit(2);
    }
    fmi2Component c =
        F.Instantiate("trajectory", fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False);
    CHECK(c != NULL);
    if (!c) exit(1);
    initialize(c);
    double t = 0.0, rate = 10.0;
    const fmi2Integer order = 1;
    static double v[MAX_VARS];
    fprintf(f, "time");
    for (size_t i = 0; i < n_outputs; i++) fprintf(f, ",\"%s\"", output_names[i]);
    fprintf(f, "\n");
    for (int k = 0; k < 100; k++) {
        double fold = rate * t;
        CHECK(F.SetReal(c, inputs, 1, &fold) == fmi2OK);
        CHECK(F.SetRealInputDerivatives(c, inputs, 1, &order, &rate) == fmi2OK);
        t = step_and_read(c, t, 1e-3, 1, v);
        fprintf(f, "%.17g", t);
        for (size_t i = 0; i < n_outputs; i++) fprintf(f, ",%.17g", v[i]);
        fprintf(f, "\n");
    }
    CHECK(F.Terminate(c) == fmi2OK);
    F.FreeInstance(c);
    CHECK(fclose(f) == 0);
}

int main(int argc, char **argv) {
    if (argc != 2 && argc != 3) {
        fprintf(stderr, "usage: %s FMU_DIR [OUTPUTS.csv]\n", argv[0]);
        return 2;
    }
    char path[4096], uri[4096 + 16], guid[128];
    char *dir = absolute_path(argv[1]);
    if (!dir) {
        perror(argv[1]);
        return 2;
    }
    snprintf(path, sizeof path, "%s/modelDescription.xml", dir);
    char *xml = read_file(path);
    read_model_description(xml, guid, sizeof guid);
    free(xml);
#ifdef _WIN32
    /* file:///C:/dir/resources: the drive path with forward slashes. */
    snprintf(uri, sizeof uri, "file:///%s/resources", dir);
    for (char *p = uri; *p; p++)
        if (*p == '\\') *p = '/';
#else
    snprintf(uri, sizeof uri, "file://%s/resources", dir);
#endif
    snprintf(path, sizeof path, "%s" BINARY, dir);
    free(dir);

    library lib = open_library(path);
    if (!lib) {
        fprintf(stderr, "host.c: cannot load %s: %s\n", path, library_error());
        return 2;
    }
#define LOAD(name) *(void **)(&F.name) = sym(lib, "fmi2" #name)
    LOAD(GetVersion);
    LOAD(GetTypesPlatform);
    LOAD(SetDebugLogging);
    LOAD(Instantiate);
    LOAD(FreeInstance);
    LOAD(SetupExperiment);
    LOAD(EnterInitializationMode);
    LOAD(ExitInitializationMode);
    LOAD(Terminate);
    LOAD(Reset);
    LOAD(GetReal);
    LOAD(SetReal);
    LOAD(GetInteger);
    LOAD(SetBoolean);
    LOAD(GetString);
    LOAD(GetFMUstate);
    LOAD(SetFMUstate);
    LOAD(FreeFMUstate);
    LOAD(SerializedFMUstateSize);
    LOAD(SerializeFMUstate);
    LOAD(DeSerializeFMUstate);
    LOAD(SetRealInputDerivatives);
    LOAD(DoStep);
    LOAD(GetBooleanStatus);
    LOAD(GetRealStatus);
    LOAD(SetTime);

    CHECK(!strcmp(F.GetVersion(), "2.0"));
    CHECK(!strcmp(F.GetTypesPlatform(), "default"));

    /* fmi2Instantiate refuses what it cannot use, with NULL. */
    CHECK(F.Instantiate("x", fmi2CoSimulation, guid, uri, NULL, fmi2False, fmi2False) == NULL);
    CHECK(F.Instantiate(NULL, fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False) ==
          NULL);
    CHECK(F.Instantiate("x", fmi2CoSimulation, NULL, uri, &callbacks, fmi2False, fmi2False) ==
          NULL);
    CHECK(F.Instantiate("x", fmi2CoSimulation, guid, NULL, &callbacks, fmi2False, fmi2False) ==
          NULL);
    CHECK(F.Instantiate("x", fmi2CoSimulation, "{not-the-guid}", uri, &callbacks, fmi2False,
                        fmi2False) == NULL);
    CHECK(strstr(last_message, "GUID mismatch") != NULL);
    CHECK(F.Instantiate("x", fmi2ModelExchange, guid, uri, &callbacks, fmi2False, fmi2False) ==
          NULL);
    CHECK(F.Instantiate("x", (fmi2Type)7, guid, uri, &callbacks, fmi2False, fmi2False) == NULL);
    CHECK(logged[fmi2Error] >= 6);

    /* Handles that are not instances: NULL, a zeroed (foreign) block, a
     * misaligned pointer. */
    static uint64_t foreign[1024];
    bad_handle(NULL);
    bad_handle(foreign);
    bad_handle((char *)foreign + 1);

    fmi2Component c =
        F.Instantiate("host", fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False);
    CHECK(c != NULL);
    if (!c) return 1;
    CHECK(F.SetDebugLogging(c, fmi2False, 0, NULL) == fmi2OK); /* all off */
    fmi2String errors[] = {"logStatusError", "logStatusFatal"};
    CHECK(F.SetDebugLogging(c, fmi2True, 2, errors) == fmi2OK); /* just these */
    CHECK(F.SetDebugLogging(c, fmi2True, 1, NULL) == fmi2Error);
    fmi2String unknown[] = {"noSuchCategory"};
    CHECK(F.SetDebugLogging(c, fmi2True, 1, unknown) == fmi2Error);
    CHECK(F.DoStep(c, 0.0, 0.01, fmi2True) == fmi2Error); /* before initialization */
    initialize(c);

    /* Value arrays: NULL with n > 0, misaligned, or a NaN input is refused;
     * n = 0 with NULL is fine. */
    double v[MAX_VARS];
    fmi2ValueReference vr_buf[2];
    const fmi2ValueReference *odd = (const fmi2ValueReference *)((const char *)vr_buf + 1);
    memcpy((char *)vr_buf + 1, &outputs[0], sizeof outputs[0]);
    CHECK(F.GetReal(c, NULL, 1, v) == fmi2Error);
    CHECK(F.GetReal(c, outputs, 1, NULL) == fmi2Error);
    CHECK(F.GetReal(c, odd, 1, v) == fmi2Error);
    CHECK(F.GetReal(c, NULL, 0, NULL) == fmi2OK);
    double nan_value = NAN;
    CHECK(F.SetReal(c, inputs, 1, &nan_value) == fmi2Error);
    CHECK(F.SetReal(c, inputs, 1, NULL) == fmi2Error);
    fmi2Integer order = 1;
    double rate = 0.0; /* accepted, and leaves the run below as it is */
    CHECK(F.SetRealInputDerivatives(c, inputs, 1, NULL, &rate) == fmi2Error);
    CHECK(F.SetRealInputDerivatives(c, inputs, 1, &order, &rate) == fmi2OK);
    fmi2Integer ints[1];
    fmi2Boolean bools[1] = {fmi2True};
    fmi2String strs[1];
    CHECK(F.GetInteger(c, NULL, 0, NULL) == fmi2OK);
    CHECK(F.GetInteger(c, outputs, 1, ints) == fmi2Error);
    CHECK(F.SetBoolean(c, outputs, 1, bools) == fmi2Error);
    CHECK(F.GetString(c, outputs, 1, strs) == fmi2Error);
    fmi2Boolean terminated = fmi2True;
    CHECK(F.GetBooleanStatus(c, fmi2Terminated, &terminated) == fmi2OK && !terminated);
    CHECK(F.GetBooleanStatus(c, (fmi2StatusKind)99, &terminated) == fmi2Error);
    CHECK(F.GetRealStatus(c, fmi2LastSuccessfulTime, NULL) == fmi2Error);
    CHECK(F.SetTime(c, 0.0) == fmi2Error); /* Model Exchange only */

    /* An input, then steps. */
    double fold = 0.5;
    CHECK(F.SetReal(c, inputs, 1, &fold) == fmi2OK);
    const double h = 0.01;
    double t = step_and_read(c, 0.0, h, 3, v);

    /* FMU states: two more steps from a saved state, again from the state
     * restored, and again from a serialized copy, give the same outputs
     * bit for bit. */
    fmi2FMUstate s = NULL, s2 = NULL;
    CHECK(F.GetFMUstate(c, NULL) == fmi2Error);
    CHECK(F.GetFMUstate(c, &s) == fmi2OK && s != NULL);
    CHECK(F.GetFMUstate(c, &s) == fmi2OK); /* overwrites in place */
    CHECK(F.SetFMUstate(c, NULL) == fmi2Error);
    CHECK(F.SetFMUstate(c, foreign) == fmi2Error);
    CHECK(strstr(last_message, "not created by this FMU") != NULL);
    static double a[MAX_VARS], b[MAX_VARS];
    step_and_read(c, t, h, 2, a);
    CHECK(F.SetFMUstate(c, s) == fmi2OK);
    step_and_read(c, t, h, 2, b);
    CHECK(memcmp(a, b, n_outputs * sizeof a[0]) == 0);

    size_t size = 0;
    CHECK(F.SerializedFMUstateSize(c, s, NULL) == fmi2Error);
    CHECK(F.SerializedFMUstateSize(c, NULL, &size) == fmi2Error);
    CHECK(F.SerializedFMUstateSize(c, s, &size) == fmi2OK && size > 0);
    fmi2Byte *bytes = malloc(size);
    CHECK(bytes != NULL);
    CHECK(F.SerializeFMUstate(c, s, bytes, size - 1) == fmi2Error);
    CHECK(F.SerializeFMUstate(c, s, NULL, size) == fmi2Error);
    CHECK(F.SerializeFMUstate(c, s, bytes, size) == fmi2OK);
    CHECK(F.DeSerializeFMUstate(c, bytes, size, NULL) == fmi2Error);
    CHECK(F.DeSerializeFMUstate(c, NULL, size, &s2) == fmi2Error && s2 == NULL);
    CHECK(F.DeSerializeFMUstate(c, "{\"no\":1}", 8, &s2) == fmi2Error && s2 == NULL);
    CHECK(F.DeSerializeFMUstate(c, bytes, size, &s2) == fmi2OK && s2 != NULL);
    /* One flipped bit, or one byte less, and the state is refused. */
    fmi2FMUstate s3 = NULL;
    bytes[size / 2] ^= 0x10;
    CHECK(F.DeSerializeFMUstate(c, bytes, size, &s3) == fmi2Error && s3 == NULL);
    CHECK(strstr(last_message, "checksum") != NULL);
    bytes[size / 2] ^= 0x10;
    CHECK(F.DeSerializeFMUstate(c, bytes, size - 1, &s3) == fmi2Error && s3 == NULL);
    free(bytes);
    CHECK(F.SetFMUstate(c, s2) == fmi2OK);
    step_and_read(c, t, h, 2, b);
    CHECK(memcmp(a, b, n_outputs * sizeof a[0]) == 0);

    CHECK(F.FreeFMUstate(c, NULL) == fmi2Error);
    CHECK(F.FreeFMUstate(c, &s) == fmi2OK && s == NULL);
    CHECK(F.FreeFMUstate(c, &s) == fmi2OK); /* *FMUstate NULL: nothing */
    fmi2FMUstate not_ours = foreign;
    CHECK(F.FreeFMUstate(c, &not_ours) == fmi2Error && not_ours == (fmi2FMUstate)foreign);
    CHECK(F.FreeFMUstate(c, &s2) == fmi2OK && s2 == NULL);

    /* Reset, a second run from the start, terminate, free. */
    CHECK(F.Reset(c) == fmi2OK);
    initialize(c);
    CHECK(F.SetReal(c, inputs, 1, &fold) == fmi2OK);
    step_and_read(c, 0.0, h, 1, v);
    /* A state the host never frees goes with its instance (valgrind would
     * report it lost); states are freed in every phase. */
    fmi2FMUstate kept = NULL, late = NULL;
    CHECK(F.GetFMUstate(c, &kept) == fmi2OK && kept != NULL);
    CHECK(F.Terminate(c) == fmi2OK);
    CHECK(F.DoStep(c, h, h, fmi2True) == fmi2Error);
    CHECK(F.GetFMUstate(c, &late) == fmi2OK);
    CHECK(F.FreeFMUstate(c, &late) == fmi2OK && late == NULL);
    F.FreeInstance(c);

    /* Two instances at once, each freed. */
    fmi2Component c1 = F.Instantiate("one", fmi2CoSimulation, guid, uri, &callbacks, fmi2False,
                                     fmi2False);
    fmi2Component c2 = F.Instantiate("two", fmi2CoSimulation, guid, uri, &callbacks, fmi2False,
                                     fmi2False);
    CHECK(c1 != NULL && c2 != NULL && c1 != c2);
    if (c1 && c2) {
        initialize(c1);
        initialize(c2);
        step_and_read(c1, 0.0, h, 1, a);
        step_and_read(c2, 0.0, h, 1, b);
        CHECK(memcmp(a, b, n_outputs * sizeof a[0]) == 0);
    }
    F.FreeInstance(c1);
    F.FreeInstance(c2);
    F.FreeInstance(NULL);
    if (argc == 3) trajectory(guid, uri, argv[2]);

    if (close_library(lib) != 0) {
        fprintf(stderr, "host.c: closing the library: %s\n", library_error());
        failures++;
    }
    printf("c_host: %d checks, %d failed (%zu inputs, %zu outputs)\n", checks, failures, n_inputs,
           n_outputs);
    return failures == 0 ? 0 : 1;
}
