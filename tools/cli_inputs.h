// The input signals of `springmass run --input FILE`: a CSV of the ports' inputs over time, as
// fmpy's write_csv writes one (and fmpy's simulate_fmu takes for the model's FMU): "time", then
// the FMU's names of the inputs it gives, force ports' P.fx P.fy P.fz [N] and motion ports' P.x
// P.y P.z [m] and P.vx P.vy P.vz [m/s].
//
// Between rows a signal is linear (a repeated time is a jump there); before the first row it has
// the first row's value, after the last the last one's. A force port pushes with the force given
// (0 in a component not named). A motion port named in the file is driven (the file's own
// `fixed` or motion no longer applies to its particle), component by component: along the
// positions given, at their slope when no velocities are given; with the velocities given,
// accelerating at their slope, from the positions given or, without them, from where the motion
// has got to; a component named neither way keeps the particle's motion in the file (its initial
// position and velocity; a fixed particle's stays put).
#pragma once

#include "springmass/model_file.h"
#include "springmass/simulation.h"

typedef struct cli_inputs cli_inputs;

// Reads the signals in the file at path for the model's ports. NULL after printing on stderr
// what is wrong, naming the file, the line and the column ("springmass run: --input F:3:7: ...").
cli_inputs* cli_inputs_read(const char* path, const sm_document* doc);

// The same from the file's text: NULL with *problem a malloc'd "LINE:COLUMN: what is wrong", or
// NULL with *problem NULL when memory runs out.
cli_inputs* cli_inputs_parse(const char* text, size_t length, const sm_document* doc, char** problem);

// Drives the particles of the motion ports the signals name, at rest if the file holds them.
sm_status cli_inputs_drive(const cli_inputs* inputs, sm_model* model);

// Gives the simulation the inputs from its current time on, up to the next change. On failure
// (a slope beyond a double: rows too close for their values) why[size] says what failed.
sm_status cli_inputs_apply(const cli_inputs* inputs, sm_simulation* sim, char* why, size_t size);

// Advances the simulation to t [s] (sm_simulation_advance_interpolated, CVODE stepping on towards
// t_stop >= t), stopping at every change of the inputs' course on the way and giving the
// simulation the inputs from there. NULL inputs: the plain advance. On failure the simulation's
// last error says why, or why[size] when the inputs could not be given.
sm_status cli_inputs_advance(const cli_inputs* inputs, sm_simulation* sim, double t, double t_stop, char* why,
                             size_t size);

void cli_inputs_destroy(cli_inputs* inputs);
