/* example_mission.c -- run a mission through the generated thermal model (prefix gt).
 *
 * Usage:  example_mission MISSION.csv > states.csv
 *
 * MISSION.csv: the header line "time_s,I_u,I_v,I_w,I_exc,T_inlet,T_ambient" (s, A RMS, A RMS,
 * A RMS, A, degC, degC), then one row per sample on a uniform grid whose step equals gt_dt_s;
 * row k is held over [t_k, t_k + dt) -- what `Mission.to_inputs(dt)` writes with pandas.
 *
 * Output: "time_s,T_<state>,..." then one row per input row with the state temperatures (degC)
 * at t_k, printed with %.17g. Every state starts at the first row's T_ambient (a cold machine).
 *
 * The model is linked statically (see codegen/ABI.md, "Building"). The library allocates
 * nothing; this program allocates the mission-length arrays and the work memory itself.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gt.h"

#define MAX_LINE 4096
#define N_COLUMNS (1 + GT_N_INPUTS)

/* Rows of the mission: times (s) and inputs, n_rows x GT_N_INPUTS, row-major. */
typedef struct {
    double* time_s;
    double* inputs;
    int n_rows;
} mission_t;

static void strip_line_end(char* line)
{
    size_t n = strlen(line);
    while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' ')) line[--n] = '\0';
}

static int check_header(const char* line, const char* path)
{
    char expected[MAX_LINE] = "time_s";
    int i;
    for (i = 0; i < GT_N_INPUTS; ++i) {
        strcat(expected, ",");
        strcat(expected, gt_input_names[i]);
    }
    if (strcmp(line, expected) != 0) {
        fprintf(stderr, "%s: header is \"%s\", expected \"%s\"\n", path, line, expected);
        return -1;
    }
    return 0;
}

/* Parse "v0,v1,...,v6" into values; returns 0 on success. */
static int parse_row(char* line, double* values)
{
    char* cursor = line;
    int column;
    for (column = 0; column < N_COLUMNS; ++column) {
        char* end;
        errno = 0;
        values[column] = strtod(cursor, &end);
        if (end == cursor || errno != 0 || !isfinite(values[column])) return -1;
        if (column < N_COLUMNS - 1 && *end != ',') return -1;
        if (column == N_COLUMNS - 1 && *end != '\0') return -1;
        cursor = end + 1;
    }
    return 0;
}

static int read_mission(const char* path, mission_t* mission)
{
    char line[MAX_LINE];
    int capacity = 0, line_number = 1;
    FILE* file = fopen(path, "r");
    if (!file) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    if (!fgets(line, sizeof line, file)) {
        fprintf(stderr, "%s: empty file\n", path);
        fclose(file);
        return -1;
    }
    strip_line_end(line);
    if (check_header(line, path) != 0) {
        fclose(file);
        return -1;
    }
    while (fgets(line, sizeof line, file)) {
        double values[N_COLUMNS];
        ++line_number;
        strip_line_end(line);
        if (line[0] == '\0') continue;
        if (parse_row(line, values) != 0) {
            fprintf(stderr, "%s:%d: expected %d finite numbers separated by commas\n", path, line_number, N_COLUMNS);
            fclose(file);
            return -1;
        }
        if (mission->n_rows == capacity) {
            double* time_s;
            double* inputs;
            capacity = capacity ? 2 * capacity : 1024;
            time_s = realloc(mission->time_s, (size_t)capacity * sizeof *time_s);
            if (time_s) mission->time_s = time_s;
            inputs = realloc(mission->inputs, (size_t)capacity * GT_N_INPUTS * sizeof *inputs);
            if (inputs) mission->inputs = inputs;
            if (!time_s || !inputs) {
                fprintf(stderr, "%s: out of memory at line %d\n", path, line_number);
                fclose(file);
                return -1;
            }
        }
        mission->time_s[mission->n_rows] = values[0];
        memcpy(mission->inputs + (size_t)mission->n_rows * GT_N_INPUTS, values + 1, GT_N_INPUTS * sizeof(double));
        ++mission->n_rows;
    }
    fclose(file);
    if (mission->n_rows == 0) {
        fprintf(stderr, "%s: no data rows\n", path);
        return -1;
    }
    return 0;
}

static int check_time_step(const mission_t* mission, const char* path)
{
    int k;
    for (k = 1; k < mission->n_rows; ++k) {
        double step = mission->time_s[k] - mission->time_s[k - 1];
        if (fabs(step - gt_dt_s) > 1e-6 * gt_dt_s) {
            fprintf(stderr, "%s: row %d is %.17g s after the previous one; the model steps by %g s\n",
                    path, k + 1, step, gt_dt_s);
            return -1;
        }
    }
    return 0;
}

static int input_index(const char* name)
{
    int i;
    for (i = 0; i < GT_N_INPUTS; ++i)
        if (strcmp(gt_input_names[i], name) == 0) return i;
    return -1;
}

static void print_states(double time_s, const double* x)
{
    int i;
    printf("%.17g", time_s);
    for (i = 0; i < GT_N_STATES; ++i) printf(",%.17g", x[i]);
    printf("\n");
}

int main(int argc, char** argv)
{
    mission_t mission = {NULL, NULL, 0};
    double x0[GT_N_STATES];
    double* states = NULL;
    double* work = NULL;
    int ambient = input_index("T_ambient");
    int i, k, status = 1;

    if (argc != 2) {
        fprintf(stderr, "usage: %s MISSION.csv > states.csv\n", argv[0]);
        return 2;
    }
    if (ambient < 0 || read_mission(argv[1], &mission) != 0 || check_time_step(&mission, argv[1]) != 0)
        goto done;
    for (i = 0; i < GT_N_STATES; ++i) x0[i] = mission.inputs[ambient];
    states = malloc((size_t)mission.n_rows * GT_N_STATES * sizeof *states);
    work = malloc(gt_work_size() * sizeof *work);
    if (!states || !work) {
        fprintf(stderr, "out of memory\n");
        goto done;
    }
    /* the last row's input would act after the last printed time: n_rows - 1 steps */
    if (gt_simulate(x0, mission.inputs, mission.n_rows - 1, states, work, gt_work_size()) != GT_OK) {
        fprintf(stderr, "gt_simulate failed\n");
        goto done;
    }
    printf("time_s");
    for (i = 0; i < GT_N_STATES; ++i) printf(",T_%s", gt_state_names[i]);
    printf("\n");
    print_states(mission.time_s[0], x0);
    for (k = 1; k < mission.n_rows; ++k) print_states(mission.time_s[k], states + (size_t)(k - 1) * GT_N_STATES);
    status = 0;
done:
    free(work);
    free(states);
    free(mission.inputs);
    free(mission.time_s);
    return status;
}
