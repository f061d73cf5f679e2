/* The Python runtime of an exported machine: found, loaded and called (see machine.h). */
#define _GNU_SOURCE
#include "machine.h"

#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <wchar.h>

#define MAX_PATHS 16
#define LINE 4096

/* resources/cosim/runtime.txt: what the FMU was exported with (key=value lines). */
typedef struct {
    char python_version[32]; /* "3.11" */
    char python[LINE];       /* the interpreter it was exported from, for messages */
    char libpython[LINE];    /* the shared libpython (empty: the Python had none) */
    char home[LINE];         /* PYTHONHOME: sys.base_prefix */
    char paths[MAX_PATHS][LINE];
    int n_paths;             /* site folders of the environment (cosim and its dependencies): a linked FMU */
    char wheels[256];        /* a portable FMU: its wheels' folder in resources/cosim ("wheels") */
    char bootstrap[256];     /* ... the script that installs them (resources/cosim/bootstrap.py) */
    char digest[128];        /* ... and the FMU's digest, which names its folder in the per-user cache */
    char module[256];        /* cosim.fmu_export.runtime */
} Runtime;

/* The functions of the CPython stable ABI used here (PyObject * is void *). */
typedef struct {
    int (*IsInitialized)(void);
    void (*InitializeEx)(int);
    void (*SetPythonHome)(const wchar_t *);
    wchar_t *(*DecodeLocale)(const char *, size_t *);
    const char *(*GetVersion)(void);
    int (*GILState_Ensure)(void);
    void (*GILState_Release)(int);
    void *(*Eval_SaveThread)(void);
    void *(*Import_ImportModule)(const char *);
    void *(*Object_GetAttrString)(void *, const char *);
    void *(*Object_CallObject)(void *, void *);
    void *(*VaBuildValue)(const char *, va_list);
    void *(*Object_Str)(void *);
    const char *(*Unicode_AsUTF8)(void *);
    long (*Long_AsLong)(void *);
    void *(*Long_AsVoidPtr)(void *);
    void (*DecRef)(void *);
    void *(*Err_Occurred)(void);
    void (*Err_Fetch)(void **, void **, void **);
    void *(*Dict_GetItemString)(void *, const char *);
} PyApi;

static PyApi py;
static int py_ready = 0;
static int py_own = 0; /* the interpreter was started here (a C importer), not the importer's own */
static pthread_mutex_t py_lock = PTHREAD_MUTEX_INITIALIZER;

/* -- messages ----------------------------------------------------------------------------------- */
void machine_log(const Machine *m, MStatus status, const char *category, const char *format, ...) {
    char message[2 * LINE];
    va_list args;
    if (m == NULL || m->sink == NULL) {
        return;
    }
    if (status == MS_OK && !m->logging_on) {
        return;
    }
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    m->sink(m, status, category, message);
}

/* Called by Python (cosim.fmu_export.runtime) through its address: one message of the machine. */
void machine_py_log(void *instance, int status, const char *category, const char *message);
void machine_py_log(void *instance, int status, const char *category, const char *message) {
    machine_log((const Machine *)instance, (MStatus)status, category, "%s", message);
}

static const char *phase_name(Phase phase) {
    switch (phase) {
    case PH_INSTANTIATED:
        return "the instantiated state";
    case PH_INITIALIZATION:
        return "initialization mode";
    case PH_STEP:
        return "step mode";
    case PH_EVENT:
        return "event mode";
    case PH_TERMINATED:
        return "the terminated state";
    default:
        return "the error state";
    }
}

int machine_enter(Machine *m, const char *fn, unsigned allowed) {
    if (m == NULL) {
        return 0;
    }
    if (((unsigned)m->phase & allowed) == 0) {
        machine_log(m, MS_ERROR, "logStatusError", "%s must not be called in %s", fn, phase_name(m->phase));
        m->phase = PH_ERROR;
        return 0;
    }
    return 1;
}

MStatus machine_result(Machine *m, MStatus status) {
    if (status >= MS_ERROR) {
        m->phase = PH_ERROR;
    }
    return status;
}

MStatus machine_unsupported(Machine *m, const char *fn) {
    if (m == NULL) {
        return MS_ERROR;
    }
    machine_log(m, MS_ERROR, "logStatusError", "%s is not supported by this FMU (a machine exported by cosim)", fn);
    return machine_result(m, MS_ERROR);
}

/* -- the runtime description -------------------------------------------------------------------- */
static int is_file(const char *path) {
    struct stat st;
    return path[0] != '\0' && stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static int is_dir(const char *path) {
    struct stat st;
    return path[0] != '\0' && stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* text into target (size bytes), cut if longer. */
static void copy(char *target, size_t size, const char *text) {
    size_t n = strlen(text);
    if (size == 0) {
        return;
    }
    if (n >= size) {
        n = size - 1;
    }
    memcpy(target, text, n);
    target[n] = '\0';
}

static int read_runtime(const Machine *m, const char *resources, Runtime *rt) {
    char path[LINE + 64];
    char line[LINE + 64];
    FILE *file;
    memset(rt, 0, sizeof *rt);
    snprintf(path, sizeof path, "%s/cosim/runtime.txt", resources);
    file = fopen(path, "r");
    if (file == NULL) {
        machine_log(m, MS_ERROR, "logStatusError",
                    "cannot read %s: the FMU's resources are incomplete (export the machine again)", path);
        return 0;
    }
    while (fgets(line, sizeof line, file) != NULL) {
        char *value = strchr(line, '=');
        size_t length = strlen(line);
        while (length > 0 && (line[length - 1] == '\n' || line[length - 1] == '\r')) {
            line[--length] = '\0';
        }
        if (value == NULL || line[0] == '#') {
            continue;
        }
        *value++ = '\0';
        if (strcmp(line, "python_version") == 0) {
            copy(rt->python_version, sizeof rt->python_version, value);
        } else if (strcmp(line, "python") == 0) {
            copy(rt->python, sizeof rt->python, value);
        } else if (strcmp(line, "libpython") == 0) {
            copy(rt->libpython, sizeof rt->libpython, value);
        } else if (strcmp(line, "home") == 0) {
            copy(rt->home, sizeof rt->home, value);
        } else if (strcmp(line, "module") == 0) {
            copy(rt->module, sizeof rt->module, value);
        } else if (strcmp(line, "path") == 0 && rt->n_paths < MAX_PATHS) {
            copy(rt->paths[rt->n_paths++], LINE, value);
        } else if (strcmp(line, "wheels") == 0) {
            copy(rt->wheels, sizeof rt->wheels, value);
        } else if (strcmp(line, "bootstrap") == 0) {
            copy(rt->bootstrap, sizeof rt->bootstrap, value);
        } else if (strcmp(line, "digest") == 0) {
            copy(rt->digest, sizeof rt->digest, value);
        }
    }
    fclose(file);
    if (rt->python_version[0] == '\0' || rt->module[0] == '\0') {
        machine_log(m, MS_ERROR, "logStatusError", "%s names no python_version or module (export the machine again)",
                    path);
        return 0;
    }
    return 1;
}

/* -- loading Python ----------------------------------------------------------------------------- */
#define BIND(handle, field, symbol)                                                                                   \
    do {                                                                                                              \
        *(void **)(&py.field) = dlsym(handle, symbol);                                                                \
        if (py.field == NULL) {                                                                                       \
            missing = symbol;                                                                                         \
        }                                                                                                             \
    } while (0)

static const char *bind(void *handle) {
    const char *missing = NULL;
    BIND(handle, IsInitialized, "Py_IsInitialized");
    BIND(handle, InitializeEx, "Py_InitializeEx");
    BIND(handle, DecodeLocale, "Py_DecodeLocale");
    BIND(handle, GetVersion, "Py_GetVersion");
    BIND(handle, GILState_Ensure, "PyGILState_Ensure");
    BIND(handle, GILState_Release, "PyGILState_Release");
    BIND(handle, Eval_SaveThread, "PyEval_SaveThread");
    BIND(handle, Import_ImportModule, "PyImport_ImportModule");
    BIND(handle, Object_GetAttrString, "PyObject_GetAttrString");
    BIND(handle, Object_CallObject, "PyObject_CallObject");
    BIND(handle, VaBuildValue, "Py_VaBuildValue");
    BIND(handle, Object_Str, "PyObject_Str");
    BIND(handle, Unicode_AsUTF8, "PyUnicode_AsUTF8");
    BIND(handle, Long_AsLong, "PyLong_AsLong");
    BIND(handle, Long_AsVoidPtr, "PyLong_AsVoidPtr");
    BIND(handle, DecRef, "Py_DecRef");
    BIND(handle, Err_Occurred, "PyErr_Occurred");
    BIND(handle, Err_Fetch, "PyErr_Fetch");
    BIND(handle, Dict_GetItemString, "PyDict_GetItemString");
    *(void **)(&py.SetPythonHome) = dlsym(handle, "Py_SetPythonHome"); /* optional: deprecated since 3.11 */
    return missing;
}

/* "3.11.7 (main, ...)" starts with "3.11." */
static int same_version(const char *version, const char *wanted) {
    size_t n = strlen(wanted);
    return strncmp(version, wanted, n) == 0 && version[n] == '.';
}

/* -- finding a Python ---------------------------------------------------------------------------- */
/* A Python with a shared libpython of the FMU's minor version, in this order: $COSIM_FMU_LIBPYTHON; the
 * one the FMU was exported with (runtime.txt), if this computer has it; python<X.Y> on the PATH (its
 * prefix's lib folder); the system's libpython<X.Y>.so.1.0 (the dynamic loader's search path). Its home
 * (PYTHONHOME) is the prefix whose lib/python<X.Y>/os.py exists: recorded, or found from the library's
 * folder; "" leaves it to Python. Each place looked at is added to `tried`, for the message. */
typedef struct {
    char library[LINE];
    char home[LINE];
    char tried[8 * LINE];
} Found;

static void note_tried(Found *f, const char *what) {
    size_t n = strlen(f->tried);
    if (n > 0) {
        copy(f->tried + n, sizeof f->tried - n, "; ");
        n = strlen(f->tried);
    }
    copy(f->tried + n, sizeof f->tried - n, what);
}

static void parent(char *path) {
    char *slash = strrchr(path, '/');
    if (slash != NULL && slash != path) {
        *slash = '\0';
    } else if (slash == path) {
        path[1] = '\0';
    }
}

static int is_home(const char *prefix, const char *version) {
    char stdlib[LINE + 64];
    snprintf(stdlib, sizeof stdlib, "%s/lib/python%s/os.py", prefix, version);
    return is_file(stdlib);
}

/* The home of a libpython at `library`: its folder's parent, or that one's parent (lib/<multiarch>/). */
static void home_of(const char *library, const char *version, char *home, size_t size) {
    char prefix[LINE];
    int i;
    home[0] = '\0';
    copy(prefix, sizeof prefix, library);
    parent(prefix); /* .../lib */
    for (i = 0; i < 2; i++) {
        parent(prefix);
        if (is_home(prefix, version)) {
            copy(home, size, prefix);
            return;
        }
    }
}

static int found_library(Found *f, const char *library, const char *version) {
    copy(f->library, sizeof f->library, library);
    home_of(library, version, f->home, sizeof f->home);
    return 1;
}

static int find_python(const Runtime *rt, Found *f) {
    const char *own = getenv("COSIM_FMU_LIBPYTHON");
    const char *path = getenv("PATH");
    char name[64], soname[64], what[4 * LINE];
    memset(f, 0, sizeof *f);
    snprintf(name, sizeof name, "python%s", rt->python_version);
    snprintf(soname, sizeof soname, "libpython%s.so.1.0", rt->python_version);
    if (own != NULL && own[0] != '\0') {
        if (is_file(own)) {
            return found_library(f, own, rt->python_version);
        }
        snprintf(what, sizeof what, "COSIM_FMU_LIBPYTHON=%s (no such file)", own);
        note_tried(f, what);
    }
    if (rt->libpython[0] != '\0') {
        if (is_file(rt->libpython)) {
            copy(f->library, sizeof f->library, rt->libpython);
            if (is_home(rt->home, rt->python_version)) {
                copy(f->home, sizeof f->home, rt->home);
            } else {
                home_of(rt->libpython, rt->python_version, f->home, sizeof f->home);
            }
            return 1;
        }
        snprintf(what, sizeof what, "%s (recorded at export: not on this computer)", rt->libpython);
        note_tried(f, what);
    }
    if (path != NULL) {
        char folders[4 * LINE];
        char *folder, *save = NULL;
        copy(folders, sizeof folders, path);
        for (folder = strtok_r(folders, ":", &save); folder != NULL; folder = strtok_r(NULL, ":", &save)) {
            char executable[LINE + 64], real[PATH_MAX], library[LINE + 128];
            const char *suffixes[] = {"lib/%s", "lib/libpython%s.so"};
            size_t k;
            snprintf(executable, sizeof executable, "%s/%s", folder, name);
            if (!is_file(executable) || realpath(executable, real) == NULL) {
                continue;
            }
            parent(real); /* .../bin */
            parent(real); /* the prefix */
            for (k = 0; k < sizeof suffixes / sizeof suffixes[0]; k++) {
                char relative[128];
                snprintf(relative, sizeof relative, suffixes[k], k == 0 ? soname : rt->python_version);
                snprintf(library, sizeof library, "%s/%s", real, relative);
                if (is_file(library)) {
                    return found_library(f, library, rt->python_version);
                }
            }
            snprintf(what, sizeof what, "%s (no shared libpython beside it in %s/lib)", executable, real);
            note_tried(f, what);
            break;
        }
    }
    {
        void *handle = dlopen(soname, RTLD_NOW | RTLD_GLOBAL);
        if (handle != NULL) {
            Dl_info info;
            void *symbol = dlsym(handle, "Py_IsInitialized");
            if (symbol != NULL && dladdr(symbol, &info) != 0 && info.dli_fname != NULL) {
                return found_library(f, info.dli_fname, rt->python_version);
            }
            return found_library(f, soname, rt->python_version);
        }
        snprintf(what, sizeof what, "%s (not on the library search path)", soname);
        note_tried(f, what);
    }
    return 0;
}

static int load_python(const Machine *m, const Runtime *rt) {
    int (*initialized)(void) = NULL;
    void *handle;
    const char *missing;
    Found found;
    if (py_ready) {
        return 1;
    }
    *(void **)(&initialized) = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (initialized != NULL && initialized()) {
        /* A Python importer (fmpy): use its interpreter; a second one in the process would break both. */
        missing = bind(RTLD_DEFAULT);
        if (missing != NULL) {
            machine_log(m, MS_ERROR, "logStatusError", "the Python of this process has no %s", missing);
            return 0;
        }
        if (!same_version(py.GetVersion(), rt->python_version)) {
            machine_log(m, MS_ERROR, "logStatusError",
                        "this process runs Python %.20s, but the FMU was exported with Python %s (%s): load it from "
                        "a Python %s process, or from a program without Python",
                        py.GetVersion(), rt->python_version, rt->python, rt->python_version);
            return 0;
        }
        py_ready = 1;
        return 1;
    }
    if (!find_python(rt, &found)) {
        if (rt->wheels[0] == '\0' && rt->libpython[0] == '\0') {
            machine_log(m, MS_ERROR, "logStatusError",
                        "the Python this FMU was exported with (%s) has no shared libpython, so the FMU runs only "
                        "inside a Python %s process (fmpy); export it from a Python built with --enable-shared",
                        rt->python, rt->python_version);
        } else {
            machine_log(m, MS_ERROR, "logStatusError",
                        "the Python runtime this FMU needs is missing: no CPython %s with a shared libpython was "
                        "found (the FMU was exported with Python %s, %s); looked at: %s. Install CPython %s with "
                        "its shared library (Debian, Ubuntu: the package libpython%s; pyenv: "
                        "PYTHON_CONFIGURE_OPTS=--enable-shared), or set COSIM_FMU_LIBPYTHON to its libpython%s.so.1.0",
                        rt->python_version, rt->python_version, rt->python, found.tried, rt->python_version,
                        rt->python_version, rt->python_version);
        }
        return 0;
    }
    if (found.home[0] == '\0') { /* Python would abort the importer at start-up without its standard library */
        machine_log(m, MS_ERROR, "logStatusError",
                    "the standard library of Python %s is missing: no lib/python%s/os.py above %s (the Python "
                    "runtime found for this FMU); install CPython %s completely, or set COSIM_FMU_LIBPYTHON to "
                    "another one",
                    rt->python_version, rt->python_version, found.library, rt->python_version);
        return 0;
    }
    handle = dlopen(found.library, RTLD_NOW | RTLD_GLOBAL);
    if (handle == NULL) {
        machine_log(m, MS_ERROR, "logStatusError", "cannot load the Python runtime %s: %s", found.library,
                    dlerror());
        return 0;
    }
    missing = bind(handle);
    if (missing != NULL) {
        machine_log(m, MS_ERROR, "logStatusError", "%s has no %s", found.library, missing);
        return 0;
    }
    if (!py.IsInitialized()) {
        if (py.SetPythonHome != NULL) {
            wchar_t *home = py.DecodeLocale(found.home, NULL);
            if (home != NULL) {
                py.SetPythonHome(home); /* kept for the life of the interpreter, as Python requires */
            }
        }
        py.InitializeEx(0); /* 0: leave the importer's signal handlers alone */
        py.Eval_SaveThread(); /* release the GIL: every call below takes it with PyGILState_Ensure */
        py_own = 1;
    }
    machine_log(m, MS_OK, "logEvents", "loaded Python %.20s from %s (home %s)", py.GetVersion(), found.library,
                found.home);
    py_ready = 1;
    return 1;
}

/* The text of the pending Python exception (and clears it), for a message. */
static void exception_text(char *text, size_t size) {
    void *type = NULL, *value = NULL, *traceback = NULL;
    void *str;
    copy(text, size, "unknown error");
    if (py.Err_Occurred() == NULL) {
        return;
    }
    py.Err_Fetch(&type, &value, &traceback);
    str = value != NULL ? py.Object_Str(value) : NULL;
    if (str != NULL) {
        const char *utf8 = py.Unicode_AsUTF8(str);
        if (utf8 != NULL) {
            copy(text, size, utf8);
        }
        py.DecRef(str);
    }
    if (py.Err_Occurred() != NULL) {
        void *t2 = NULL, *v2 = NULL, *tb2 = NULL;
        py.Err_Fetch(&t2, &v2, &tb2);
        if (t2 != NULL) py.DecRef(t2);
        if (v2 != NULL) py.DecRef(v2);
        if (tb2 != NULL) py.DecRef(tb2);
    }
    if (type != NULL) py.DecRef(type);
    if (value != NULL) py.DecRef(value);
    if (traceback != NULL) py.DecRef(traceback);
}

/* Call callable(*args) (args from a Py_BuildValue tuple format); a new reference or NULL after a log. */
static void *call(const Machine *m, void *callable, const char *what, const char *format, va_list args) {
    char text[LINE];
    void *arguments = py.VaBuildValue(format, args);
    void *out = NULL;
    if (arguments != NULL) {
        out = py.Object_CallObject(callable, arguments);
        py.DecRef(arguments);
    }
    if (out == NULL) {
        exception_text(text, sizeof text);
        machine_log(m, MS_ERROR, "logStatusError", "%s failed in Python: %s", what, text);
    }
    return out;
}

static void *call_va(const Machine *m, void *callable, const char *what, const char *format, ...) {
    void *out;
    va_list args;
    va_start(args, format);
    out = call(m, callable, what, format, args);
    va_end(args);
    return out;
}

static void *call_attr(const Machine *m, void *object, const char *name, const char *format, ...) {
    char text[LINE];
    void *callable = py.Object_GetAttrString(object, name);
    void *out;
    va_list args;
    if (callable == NULL) {
        exception_text(text, sizeof text);
        machine_log(m, MS_ERROR, "logStatusError", "%s: %s", name, text);
        return NULL;
    }
    va_start(args, format);
    out = call(m, callable, name, format, args);
    va_end(args);
    py.DecRef(callable);
    return out;
}

/* An address returned by a method of the slave (a Python int). */
static void *address(const Machine *m, void *slave, const char *method) {
    void *result = call_attr(m, slave, method, "()");
    void *pointer;
    if (result == NULL) {
        return NULL;
    }
    pointer = py.Long_AsVoidPtr(result);
    py.DecRef(result);
    return pointer;
}

static int add_site_folders(const Machine *m, const Runtime *rt) {
    void *site = py.Import_ImportModule("site");
    char text[LINE];
    int i, ok = 1;
    if (site == NULL) {
        exception_text(text, sizeof text);
        machine_log(m, MS_ERROR, "logStatusError", "cannot import site: %s", text);
        return 0;
    }
    for (i = 0; i < rt->n_paths && ok; i++) {
        void *result;
        if (!is_dir(rt->paths[i])) {
            machine_log(m, MS_ERROR, "logStatusError",
                        "the Python environment this FMU needs is missing: %s does not exist (recorded at export "
                        "from %s; it holds cosim and its dependencies): export the machine again from an "
                        "environment that exists",
                        rt->paths[i], rt->python);
            ok = 0;
            break;
        }
        result = call_attr(m, site, "addsitedir", "(s)", rt->paths[i]);
        if (result == NULL) {
            ok = 0;
        } else {
            py.DecRef(result);
        }
    }
    py.DecRef(site);
    return ok;
}

/* A portable FMU: resources/cosim/bootstrap.py installs the wheels it carries (once, into the per-user
 * cache) and puts them on sys.path. */
static int install_wheels(const Machine *m, const Runtime *rt, const char *resources) {
    char script[2 * LINE];
    void *runpy, *globals, *prepare, *args, *folder;
    int ok = 0;
    snprintf(script, sizeof script, "%s/cosim/%s", resources, rt->bootstrap[0] ? rt->bootstrap : "bootstrap.py");
    if (!is_file(script)) {
        machine_log(m, MS_ERROR, "logStatusError",
                    "%s is missing: the FMU's resources are incomplete (export the machine again)", script);
        return 0;
    }
    runpy = py.Import_ImportModule("runpy");
    if (runpy == NULL) {
        char text[LINE];
        exception_text(text, sizeof text);
        machine_log(m, MS_ERROR, "logStatusError", "cannot import runpy: %s", text);
        return 0;
    }
    globals = call_attr(m, runpy, "run_path", "(s)", script);
    py.DecRef(runpy);
    if (globals == NULL) {
        return 0;
    }
    prepare = py.Dict_GetItemString(globals, "prepare"); /* borrowed */
    if (prepare == NULL) {
        machine_log(m, MS_ERROR, "logStatusError", "%s has no prepare() (export the machine again)", script);
    } else {
        args = call_va(m, prepare, "installing the FMU's Python packages", "(ssi)", resources, rt->digest, py_own);
        if (args != NULL) {
            folder = py.Object_Str(args);
            machine_log(m, MS_OK, "logEvents", "cosim and its packages from %s",
                        folder != NULL && py.Unicode_AsUTF8(folder) != NULL ? py.Unicode_AsUTF8(folder) : "?");
            if (folder != NULL) {
                py.DecRef(folder);
            }
            py.DecRef(args);
            ok = 1;
        }
    }
    py.DecRef(globals);
    return ok;
}

/* -- instances ---------------------------------------------------------------------------------- */
static char *duplicate(const char *text) {
    size_t n = strlen(text) + 1;
    char *out = (char *)malloc(n);
    if (out != NULL) {
        memcpy(out, text, n);
    }
    return out;
}

Machine *machine_new(int fmi_version, const char *name, const char *token, const char *resources, MachineSink sink,
                     void *env, const void *callbacks, void (*log_fn)(void), int logging_on, int event_mode_used,
                     int early_return_allowed) {
    Runtime *rt;
    Machine *m = (Machine *)calloc(1, sizeof(Machine));
    void *module = NULL, *slave = NULL, *count = NULL;
    int gil, ok = 0;
    if (m == NULL) {
        return NULL;
    }
    m->name = duplicate(name != NULL ? name : "machine");
    m->fmi_version = fmi_version;
    m->sink = sink;
    m->env = env;
    m->callbacks = callbacks;
    m->log_fn = log_fn;
    m->logging_on = logging_on;
    m->event_mode_used = event_mode_used;
    m->phase = PH_INSTANTIATED;
    rt = (Runtime *)malloc(sizeof(Runtime));
    if (m->name == NULL || rt == NULL || resources == NULL || !read_runtime(m, resources, rt)) {
        if (resources == NULL) {
            machine_log(m, MS_ERROR, "logStatusError", "the importer gave no resource location");
        }
        free(rt);
        machine_free(m);
        return NULL;
    }
    pthread_mutex_lock(&py_lock);
    ok = load_python(m, rt);
    pthread_mutex_unlock(&py_lock);
    if (!ok) {
        free(rt);
        machine_free(m);
        return NULL;
    }
    ok = 0;
    gil = py.GILState_Ensure();
    if (rt->wheels[0] != '\0' ? install_wheels(m, rt, resources) : add_site_folders(m, rt)) {
        module = py.Import_ImportModule(rt->module);
        if (module == NULL) {
            char text[LINE];
            exception_text(text, sizeof text);
            machine_log(m, MS_ERROR, "logStatusError", "cannot import %s from %s: %s", rt->module,
                        rt->wheels[0] != '\0' ? "the FMU's own packages" : rt->n_paths > 0 ? rt->paths[0]
                                                                               : "(no environment recorded)", text);
        } else {
            slave = call_attr(m, module, "instantiate", "(sssiiiiKK)", resources, m->name, token != NULL ? token : "",
                              fmi_version, event_mode_used, early_return_allowed, logging_on,
                              (unsigned long long)(uintptr_t)machine_py_log, (unsigned long long)(uintptr_t)m);
            py.DecRef(module);
        }
    }
    if (slave != NULL) {
        m->values = (double *)address(m, slave, "values_address");
        m->kinds = (const unsigned char *)address(m, slave, "kinds_address");
        m->step = (const double *)address(m, slave, "step_address");
        count = call_attr(m, slave, "n_values", "()");
        if (count != NULL) {
            m->n_values = (size_t)py.Long_AsLong(count);
            py.DecRef(count);
        }
        ok = m->values != NULL && m->kinds != NULL && m->step != NULL && m->n_values > 0;
        m->slave = slave;
    }
    py.GILState_Release(gil);
    free(rt);
    if (!ok) {
        machine_free(m);
        return NULL;
    }
    return m;
}

void machine_free(Machine *m) {
    if (m == NULL) {
        return;
    }
    if (m->slave != NULL) {
        int gil = py.GILState_Ensure();
        void *result = call_attr(m, m->slave, "free", "()");
        if (result != NULL) {
            py.DecRef(result);
        }
        py.DecRef(m->slave);
        py.GILState_Release(gil);
    }
    free(m->name);
    free(m);
}

MStatus machine_call(Machine *m, const char *method, const char *format, ...) {
    void *callable, *result;
    long status = MS_ERROR;
    va_list args;
    int gil = py.GILState_Ensure();
    callable = py.Object_GetAttrString(m->slave, method);
    if (callable == NULL) {
        char text[LINE];
        exception_text(text, sizeof text);
        machine_log(m, MS_ERROR, "logStatusError", "%s: %s", method, text);
    } else {
        va_start(args, format);
        result = call(m, callable, method, format, args);
        va_end(args);
        py.DecRef(callable);
        if (result != NULL) {
            status = py.Long_AsLong(result);
            py.DecRef(result);
        }
    }
    py.GILState_Release(gil);
    if (status < MS_OK || status > MS_FATAL) {
        status = MS_ERROR;
    }
    return machine_result(m, (MStatus)status);
}

/* -- variables ---------------------------------------------------------------------------------- */
static const char *type_name(int type) {
    return type == VK_FLOAT64 ? "Float64" : type == VK_INT32 ? "Int32" : "Boolean";
}

static int check_vr(Machine *m, const char *fn, int type, unsigned vr) {
    if (vr >= m->n_values || (m->kinds[vr] & VK_TYPE) == 0) {
        machine_log(m, MS_ERROR, "logStatusError", "%s: no variable has value reference %u", fn, vr);
        return 0;
    }
    if ((m->kinds[vr] & VK_TYPE) != type) {
        machine_log(m, MS_ERROR, "logStatusError", "%s: value reference %u is a %s, not a %s", fn, vr,
                    type_name(m->kinds[vr] & VK_TYPE), type_name(type));
        return 0;
    }
    return 1;
}

MStatus machine_get(Machine *m, const char *fn, int type, const unsigned *vr, size_t n, void *values) {
    size_t i;
    if (n > 0 && (vr == NULL || values == NULL)) {
        machine_log(m, MS_ERROR, "logStatusError", "%s: a NULL array", fn);
        return machine_result(m, MS_ERROR);
    }
    for (i = 0; i < n; i++) {
        double value;
        if (!check_vr(m, fn, type, vr[i])) {
            return machine_result(m, MS_ERROR);
        }
        value = m->values[vr[i]];
        if (type == VK_FLOAT64) {
            ((double *)values)[i] = value;
        } else if (type == VK_INT32) {
            ((int32_t *)values)[i] = (int32_t)value;
        } else if (m->fmi_version == 3) {
            ((bool *)values)[i] = value != 0.0;
        } else {
            ((int *)values)[i] = value != 0.0;
        }
    }
    return MS_OK;
}

MStatus machine_set(Machine *m, const char *fn, int type, const unsigned *vr, size_t n, const void *values) {
    size_t i;
    if (n > 0 && (vr == NULL || values == NULL)) {
        machine_log(m, MS_ERROR, "logStatusError", "%s: a NULL array", fn);
        return machine_result(m, MS_ERROR);
    }
    for (i = 0; i < n; i++) {
        if (!check_vr(m, fn, type, vr[i])) {
            return machine_result(m, MS_ERROR);
        }
        if ((m->kinds[vr[i]] & VK_INPUT) == 0) {
            machine_log(m, MS_ERROR, "logStatusError", "%s: value reference %u is not an input", fn, vr[i]);
            return machine_result(m, MS_ERROR);
        }
    }
    for (i = 0; i < n; i++) {
        double value;
        if (type == VK_FLOAT64) {
            value = ((const double *)values)[i];
        } else if (type == VK_INT32) {
            value = (double)((const int32_t *)values)[i];
        } else if (m->fmi_version == 3) {
            value = ((const bool *)values)[i] ? 1.0 : 0.0;
        } else {
            value = ((const int *)values)[i] ? 1.0 : 0.0;
        }
        m->values[vr[i]] = value;
    }
    return MS_OK;
}
