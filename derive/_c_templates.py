"""C source templates of the exported model: wrapper header and source, standalone driver,
Makefile. Filled with :meth:`str.format`-free ``$``-placeholders (``string.Template``) so
C braces need no escaping."""

from __future__ import annotations

from string import Template

__all__ = ["HEADER", "WRAPPER", "DRIVER", "MAKEFILE"]

HEADER = Template("""\
/* $name.h - slosh analog model exported by slosh-analogs (derive.export_c).
 *
 * Model: $model
 * Degrees of freedom:
$dof_table
 * States x = [q; qd], inputs u, parameters p, outputs y; SI units.
 * Integrator: classical RK4, $substeps substep(s) per call of ${name}_step.
 * No runtime dependency on CasADi or Python; C99 with <math.h>.
 *
 * States ($nx):
$state_table
 * Inputs ($nu):
$input_table
 * Parameters ($np), defaults = exported (fitted) values:
$param_table
 * Outputs ($ny): force and torque the transducer/mount applies to the tank assembly,
 * in tank-frame components, torque about the tank origin O (tank bottom, on the axis):
$output_table
 */
#ifndef ${NAME}_H
#define ${NAME}_H

#ifdef __cplusplus
extern "C" {
#endif

#define ${NAME}_NX $nx
#define ${NAME}_NU $nu
#define ${NAME}_NP $np
#define ${NAME}_NY $ny
#define ${NAME}_SUBSTEPS $substeps
/* Inputs per step for ${name}_step_stages: at the 2*SUBSTEPS+1 equally spaced stage times. */
#define ${NAME}_NSTAGES $nstages

extern const char *const ${name}_state_names[${NAME}_NX + 1];
extern const char *const ${name}_state_units[${NAME}_NX + 1];
extern const char *const ${name}_input_names[${NAME}_NU + 1];
extern const char *const ${name}_input_units[${NAME}_NU + 1];
extern const char *const ${name}_parameter_names[${NAME}_NP + 1];
extern const char *const ${name}_parameter_units[${NAME}_NP + 1];
extern const char *const ${name}_output_names[${NAME}_NY + 1];
extern const char *const ${name}_output_units[${NAME}_NY + 1];
/* Exported parameter values (NaN where the model had none: nothing in rhs/step needs them). */
extern const double ${name}_default_parameters[${NAME}_NP + 1];

/* xdot = f(x, u, p, t). Returns 0 on success. */
int ${name}_rhs(const double *x, const double *u, const double *p, double t, double *xdot);
/* y = outputs(x, u, p, t). Returns 0 on success. */
int ${name}_outputs(const double *x, const double *u, const double *p, double t, double *y);
/* One step of length dt (s) from time t, inputs u held constant over the step;
 * x is overwritten with the state at t + dt. Returns 0 on success. */
int ${name}_step(double *x, const double *u, const double *p, double t, double dt);
/* One step with inputs at the stage times t + dt*j/(2*SUBSTEPS), j = 0..2*SUBSTEPS:
 * U[j*NU + i] is input i at stage j (exactly what slosh's simulate(..., RK4()) uses). */
int ${name}_step_stages(double *x, const double *U, const double *p, double t, double dt);

#ifdef __cplusplus
}
#endif
#endif
""")

WRAPPER = Template("""\
/* $name.c - plain C interface around the CasADi-generated code in ${name}_casadi.c. */
#include <math.h>
#include "$name.h"
#include "${name}_casadi.h"

const char *const ${name}_state_names[${NAME}_NX + 1] = {$state_names};
const char *const ${name}_state_units[${NAME}_NX + 1] = {$state_units};
const char *const ${name}_input_names[${NAME}_NU + 1] = {$input_names};
const char *const ${name}_input_units[${NAME}_NU + 1] = {$input_units};
const char *const ${name}_parameter_names[${NAME}_NP + 1] = {$param_names};
const char *const ${name}_parameter_units[${NAME}_NP + 1] = {$param_units};
const char *const ${name}_output_names[${NAME}_NY + 1] = {$output_names};
const char *const ${name}_output_units[${NAME}_NY + 1] = {$output_units};
const double ${name}_default_parameters[${NAME}_NP + 1] = {$param_values};

/* Work sizes of the generated functions, known at export time (no allocation). */
#define ${NAME}_SZ_ARG $sz_arg
#define ${NAME}_SZ_RES $sz_res
#define ${NAME}_SZ_IW $sz_iw
#define ${NAME}_SZ_W $sz_w

typedef int (*${name}_fn)(const casadi_real **arg, casadi_real **res, casadi_int *iw,
                          casadi_real *w, int mem);

static int ${name}_call(${name}_fn f, const double *a0, const double *a1, const double *a2,
                        double a3, double a4, double *r0) {
    const casadi_real *arg[${NAME}_SZ_ARG];
    casadi_real *res[${NAME}_SZ_RES];
    casadi_int iw[${NAME}_SZ_IW];
    casadi_real w[${NAME}_SZ_W];
    int i;
    for (i = 0; i < ${NAME}_SZ_ARG; ++i) arg[i] = 0;
    for (i = 0; i < ${NAME}_SZ_RES; ++i) res[i] = 0;
    arg[0] = a0;
    arg[1] = a1;
    arg[2] = a2;
    arg[3] = &a3;
    arg[4] = &a4;
    res[0] = r0;
    return f(arg, res, iw, w, 0);
}

int ${name}_rhs(const double *x, const double *u, const double *p, double t, double *xdot) {
    return ${name}_call(${name}_cg_rhs, x, u, p, t, 0.0, xdot);
}

int ${name}_outputs(const double *x, const double *u, const double *p, double t, double *y) {
    return ${name}_call(${name}_cg_outputs, x, u, p, t, 0.0, y);
}

int ${name}_step(double *x, const double *u, const double *p, double t, double dt) {
    double xn[${NAME}_NX + 1];
    int i, status = ${name}_call(${name}_cg_step, x, u, p, t, dt, xn);
    for (i = 0; i < ${NAME}_NX; ++i) x[i] = xn[i];
    return status;
}

int ${name}_step_stages(double *x, const double *U, const double *p, double t, double dt) {
    double xn[${NAME}_NX + 1];
    int i, status = ${name}_call(${name}_cg_step_stages, x, U, p, t, dt, xn);
    for (i = 0; i < ${NAME}_NX; ++i) x[i] = xn[i];
    return status;
}
""")

DRIVER = Template("""\
/* simulate_main.c - standalone driver of the exported model $name.
 *
 * usage: simulate [--params FILE] [--stages] INPUT.csv OUTPUT.csv
 *
 * INPUT.csv: header "time$input_header", then one row per time (s, SI units).
 *   Default: outputs at every input row; within each interval the inputs at the RK4 stage
 *   times are interpolated linearly between the rows.
 *   --stages: the rows are at the RK4 stage times (2*SUBSTEPS rows per step, as in
 *   slosh's simulate with RK4); outputs at every (2*SUBSTEPS)-th row.
 * --params FILE: lines "name,value" overriding parameter defaults, or setting the
 *   initial value of a state by its name (default initial state: all zero); '#' comments.
 * OUTPUT.csv: header "time,<states>,<outputs>", %.17g.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "$name.h"

#define LINE_MAX_CHARS 65536

static int find_name(const char *const *names, int n, const char *key) {
    int i;
    for (i = 0; i < n; ++i) {
        if (strcmp(names[i], key) == 0) return i;
    }
    return -1;
}

static char *trim(char *s) {
    char *end;
    while (*s == ' ' || *s == '\\t') ++s;
    end = s + strlen(s);
    while (end > s && (end[-1] == '\\n' || end[-1] == '\\r' || end[-1] == ' ' || end[-1] == '\\t')) --end;
    *end = '\\0';
    return s;
}

static int read_params(const char *path, double *p, double *x0) {
    char line[LINE_MAX_CHARS];
    int row = 0;
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "simulate: cannot open parameter file %s\\n", path);
        return 1;
    }
    while (fgets(line, sizeof line, f)) {
        char *s = trim(line), *comma, *end, *key;
        double v;
        int i;
        ++row;
        if (*s == '\\0' || *s == '#') continue;
        comma = strchr(s, ',');
        if (!comma) {
            fprintf(stderr, "simulate: %s:%d: expected name,value, found '%s'\\n", path, row, s);
            fclose(f);
            return 1;
        }
        *comma = '\\0';
        key = trim(s);
        v = strtod(comma + 1, &end);
        if (end == comma + 1) {
            if (strcmp(key, "name") == 0) continue; /* header line */
            fprintf(stderr, "simulate: %s:%d: value of '%s' is not a number\\n", path, row, key);
            fclose(f);
            return 1;
        }
        if ((i = find_name(${name}_parameter_names, ${NAME}_NP, key)) >= 0) {
            p[i] = v;
        } else if ((i = find_name(${name}_state_names, ${NAME}_NX, key)) >= 0) {
            x0[i] = v;
        } else {
            fprintf(stderr, "simulate: %s:%d: unknown parameter or state '%s'\\n", path, row, key);
            fclose(f);
            return 1;
        }
    }
    fclose(f);
    return 0;
}

/* Reads the input CSV into a newly allocated row-major array of (1 + NU) columns. */
static double *read_inputs(const char *path, long *nrows) {
    char line[LINE_MAX_CHARS];
    long cap = 1024, n = 0, row = 1;
    const int ncol = 1 + ${NAME}_NU;
    double *data;
    char *tok, *s;
    int j;
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "simulate: cannot open input file %s\\n", path);
        return NULL;
    }
    if (!fgets(line, sizeof line, f)) {
        fprintf(stderr, "simulate: %s is empty; expected header time$input_header\\n", path);
        fclose(f);
        return NULL;
    }
    s = trim(line);
    tok = strtok(s, ",");
    for (j = 0; j < ncol; ++j) {
        const char *want = j == 0 ? "time" : ${name}_input_names[j - 1];
        if (!tok || strcmp(trim(tok), want) != 0) {
            fprintf(stderr, "simulate: %s: header column %d must be '%s', found '%s' "
                    "(expected header: time$input_header)\\n", path, j + 1, want, tok ? tok : "");
            fclose(f);
            return NULL;
        }
        tok = strtok(NULL, ",");
    }
    data = (double *)malloc((size_t)(cap * ncol) * sizeof(double));
    while (data && fgets(line, sizeof line, f)) {
        char *p = trim(line), *end;
        ++row;
        if (*p == '\\0') continue;
        if (n == cap) {
            double *grown;
            cap *= 2;
            grown = (double *)realloc(data, (size_t)(cap * ncol) * sizeof(double));
            if (!grown) {
                free(data);
                data = NULL;
                break;
            }
            data = grown;
        }
        for (j = 0; j < ncol; ++j) {
            data[n * ncol + j] = strtod(p, &end);
            if (end == p || (j < ncol - 1 && *end != ',')) {
                fprintf(stderr, "simulate: %s:%ld: expected %d comma-separated numbers\\n",
                        path, row, ncol);
                free(data);
                fclose(f);
                return NULL;
            }
            p = end + 1;
        }
        if (n > 0 && !(data[n * ncol] > data[(n - 1) * ncol])) {
            fprintf(stderr, "simulate: %s:%ld: time must increase\\n", path, row);
            free(data);
            fclose(f);
            return NULL;
        }
        ++n;
    }
    fclose(f);
    if (!data) fprintf(stderr, "simulate: out of memory reading %s\\n", path);
    *nrows = n;
    return data;
}

static void write_row(FILE *f, double t, const double *x, const double *u, const double *p) {
    double y[${NAME}_NY + 1];
    int i;
    ${name}_outputs(x, u, p, t, y);
    fprintf(f, "%.17g", t);
    for (i = 0; i < ${NAME}_NX; ++i) fprintf(f, ",%.17g", x[i]);
    for (i = 0; i < ${NAME}_NY; ++i) fprintf(f, ",%.17g", y[i]);
    fputc('\\n', f);
}

int main(int argc, char **argv) {
    double p[${NAME}_NP + 1], x[${NAME}_NX + 1];
    double U[${NAME}_NU * ${NAME}_NSTAGES + 1];
    const char *param_path = NULL, *in_path = NULL, *out_path = NULL;
    const int ncol = 1 + ${NAME}_NU, stride = ${NAME}_NSTAGES - 1;
    int stages = 0, a, i, j;
    long n, k;
    double *data;
    FILE *out;
    for (a = 1; a < argc; ++a) {
        if (strcmp(argv[a], "--params") == 0 && a + 1 < argc) {
            param_path = argv[++a];
        } else if (strcmp(argv[a], "--stages") == 0) {
            stages = 1;
        } else if (!in_path) {
            in_path = argv[a];
        } else if (!out_path) {
            out_path = argv[a];
        } else {
            in_path = NULL;
            break;
        }
    }
    if (!in_path || !out_path) {
        fprintf(stderr, "usage: %s [--params FILE] [--stages] INPUT.csv OUTPUT.csv\\n", argv[0]);
        return 2;
    }
    for (i = 0; i < ${NAME}_NP; ++i) p[i] = ${name}_default_parameters[i];
    for (i = 0; i < ${NAME}_NX; ++i) x[i] = 0.0;
    if (param_path && read_params(param_path, p, x)) return 2;
    data = read_inputs(in_path, &n);
    if (!data) return 2;
    if (n < 1 || (stages && (n - 1) % stride != 0)) {
        fprintf(stderr, "simulate: %s: %ld rows; --stages needs 1 + %d*k rows\\n", in_path, n, stride);
        free(data);
        return 2;
    }
    out = fopen(out_path, "w");
    if (!out) {
        fprintf(stderr, "simulate: cannot write %s\\n", out_path);
        free(data);
        return 2;
    }
    fprintf(out, "time");
    for (i = 0; i < ${NAME}_NX; ++i) fprintf(out, ",%s", ${name}_state_names[i]);
    for (i = 0; i < ${NAME}_NY; ++i) fprintf(out, ",%s", ${name}_output_names[i]);
    fputc('\\n', out);
    write_row(out, data[0], x, data + 1, p);
    if (stages) {
        for (k = 0; k + stride < n; k += stride) {
            double t0 = data[k * ncol], t1 = data[(k + stride) * ncol];
            for (j = 0; j < ${NAME}_NSTAGES; ++j)
                for (i = 0; i < ${NAME}_NU; ++i) U[j * ${NAME}_NU + i] = data[(k + j) * ncol + 1 + i];
            ${name}_step_stages(x, U, p, t0, t1 - t0);
            write_row(out, t1, x, data + (k + stride) * ncol + 1, p);
        }
    } else {
        for (k = 0; k + 1 < n; ++k) {
            double t0 = data[k * ncol], t1 = data[(k + 1) * ncol];
            const double *u0 = data + k * ncol + 1, *u1 = data + (k + 1) * ncol + 1;
            for (j = 0; j < ${NAME}_NSTAGES; ++j) {
                double s = (double)j / (double)stride;
                for (i = 0; i < ${NAME}_NU; ++i) U[j * ${NAME}_NU + i] = u0[i] + s * (u1[i] - u0[i]);
            }
            ${name}_step_stages(x, U, p, t0, t1 - t0);
            write_row(out, t1, x, u1, p);
        }
    }
    fclose(out);
    free(data);
    return 0;
}
""")

MAKEFILE = Template("""\
# Builds the standalone driver and a static library of the exported model $name.
CC ?= cc
CFLAGS ?= -std=c99 -Wall -Wextra -O2
LDLIBS = -lm
OBJS = $name.o ${name}_casadi.o

all: simulate lib$name.a

simulate: simulate_main.o $$(OBJS)
\t$$(CC) $$(CFLAGS) -o $$@ $$^ $$(LDLIBS)

lib$name.a: $$(OBJS)
\tar rcs $$@ $$^

%.o: %.c $name.h ${name}_casadi.h
\t$$(CC) $$(CFLAGS) -c -o $$@ $$<

clean:
\trm -f simulate lib$name.a *.o

.PHONY: all clean
""")
