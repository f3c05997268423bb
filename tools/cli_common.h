// Helpers shared by the subcommands: parameter overrides, directories and VTK output.
#pragma once

#include "cli_outputs.h"
#include "cli_shown.h"

#include "springmass/model_file.h"

#include <stdbool.h>
#include <stdio.h>

/// Reads text as a finite decimal number, as a model file writes numbers: an optional sign,
/// digits with an optional decimal point, an optional exponent (`-1.5e-3`, `.5`, `2.`); nothing
/// before or after it. Hexadecimal (`0x10`), `inf`, `nan` and spaces are refused, though strtod
/// takes them. A number below the smallest normal double is taken as strtod rounds it (1e-320),
/// as in a model file. Returns false, *value unchanged, when text is not such a number.
bool cli_parse_number(const char* text, double* value);

/// A count on the command line: a number as cli_parse_number takes it (1000, 1e3) that is whole
/// and from min to max. Returns false, *value unchanged, otherwise.
bool cli_parse_count(const char* text, double min, double max, long* value);

/// The index of the parameter a "NAME=VALUE" setting names, or -1 if it is malformed or names none.
int32_t cli_setting_parameter(const sm_document* doc, const char* setting);

/// Applies `count` "NAME=VALUE" settings (--set options) to the document's parameters, all at once
/// (values valid only together are taken in any order; a parameter given twice takes the last).
/// Returns 0 on success; otherwise prints the error with the command's name and returns the exit
/// status: 2 for a malformed setting (a usage error), 1 for an unknown parameter or values the
/// model refuses (the document then unchanged).
int cli_set_parameters(const char* command, sm_document* doc, const char* const* settings, int count);

/// An argument of subcommand `command` that none of its options took: the model file when none
/// was given yet (returns 0, *model set); else a usage error printed on stderr (returns 2): an
/// unknown option or one missing its value (an argument starting with '-', "-" alone excepted),
/// or a second model file. The caller prints its usage after it.
int cli_model_argument(const char* command, const char* arg, const char** model);

/// After the arguments: 0 when a model file was given, else the usage error printed (2).
int cli_model_given(const char* command, const char* model);

/// Loads the model file at path, applies the settings and builds the model. Returns 0 with *doc
/// and *model set (the caller destroys both); otherwise prints the error with the command's name,
/// leaves both NULL and returns the exit status (as cli_set_parameters, 1 for a bad model file).
int cli_load_model(const char* command, const char* path, const char* const* settings, int count,
                   sm_document** doc, sm_model** model);

/// Degrees of freedom above which a dense solve (modes' eigensolver, a statics Newton step)
/// takes minutes: its time grows as their cube. Measured on a 2-core machine: all modes of
/// 1500 degrees of freedom 12 s, of 3000 more than 2 minutes; statics 0.9 s per iteration at 1500.
#define CLI_DENSE_LIMIT 2000

/// Prints on stderr that a dense solve of `dof` unknowns the user asked for will take long, when
/// dof is above CLI_DENSE_LIMIT.
void cli_note_dense(const char* command, size_t dof);

/// Prints a warning on `f` (each line starting with `prefix`) and returns true when the absolute
/// tolerances of `def` are coarse for the model (sm_tolerances_coarse: both above
/// SM_COARSE_TOLERANCE times its sm_motion_scales).
bool cli_warn_coarse_tolerances(FILE* f, const char* prefix, const sm_model* model,
                                const sm_simulation_def* def);

/// Prints a warning on `f` (starting with `prefix`) and returns true when the velocities' absolute
/// tolerance of `def` is too tight for the round-off of the model's forces (sm_tolerances_tight),
/// naming the spring, with the particles' names of `doc`.
bool cli_warn_tight_tolerances(FILE* f, const char* prefix, const sm_document* doc, const sm_model* model,
                               const sm_simulation_def* def);

/// Most output rows `springmass run` writes: an interval given by mistake in the wrong unit
/// would otherwise fill the disk.
#define CLI_MAX_ROWS 1e9

/// Output rows of a run to t_end [s] every interval [s]: one at each k * interval and the last at
/// t_end (within a relative 1e-9, k * interval is t_end itself), at least that one; -1 when that
/// is more than CLI_MAX_ROWS.
long cli_output_rows(double t_end, double interval);

/// Creates a directory if it does not exist; prints the error and returns -1 on failure (also
/// when a file that is not a directory has its name).
int cli_make_directory(const char* command, const char* dir);

/// Writes a message of the library that names particles and springs by index ("particle 12",
/// "particles 3 and 4", "spring 30") with the names the model file gives them: "particle 12
/// (cloth[0,12])", "spring 30 (between cloth[2,6] and cloth[2,7])"; the rest as it is.
void cli_write_named(FILE* f, const sm_document* doc, const sm_model* model, const char* message);

/// A library message without the name of the analysis that begins it ("statics: no equilibrium
/// ..." gives "no equilibrium ..."): the tool's own message already names its command and model.
const char* cli_without_prefix(const char* message, const char* prefix);

/// Writes a particle's name or the description of a model file as sm_text_for_terminal shows it:
/// what a terminal would act on or not show, escaped; then spaces up to `width` characters.
void cli_write_text(FILE* f, const char* text, int width);

/// Writes prefix, text and suffix as one CSV field: quoted, with quotes doubled, when any holds a
/// comma or a quote (a particle's name may; RFC 4180), as it is otherwise.
void cli_csv_field(FILE* f, const char* prefix, const char* text, const char* suffix);

/// Writes ",value" as one CSV field, value in the shortest text that reads back to exactly it
/// (sm_format_number: 0.03 as 0.03, not 0.029999999999999999).
void cli_csv_number(FILE* f, double value);

/// Writes the n particles' positions x [m] as the text of VTK points, one particle to a line, each
/// coordinate in the shortest text that reads back to exactly it (sm_format_number). Nine
/// significant digits, enough for the other fields, are not for points: the geometry is their
/// differences, so a model 100 km from the origin would lose its 1 cm springs' shape to 0.5 mm.
void cli_vtk_points(FILE* f, int32_t n, const double* x);

/// Opens a legacy VTK polydata file, one of `outputs` (NULL: directly), and writes the particles
/// at x [m] as points and the springs as lines (only the enabled ones, so that broken springs
/// disappear). Follow with cli_vtk_vectors for point data, then cli_close. Prints the error and
/// returns NULL on failure.
FILE* cli_vtk_open(cli_outputs* outputs, const char* command, const char* path, const char* title,
                   const sm_model* model, const double* x);

/// Writes one vector field of point data (3 values per particle); `first` for the first field.
void cli_vtk_vectors(FILE* f, const char* name, int32_t count, const double* values, bool first);

/// Checks the folder an option writes (NULL: none given) before anything runs: "-", standard
/// output for a file, holds no folder of files (and is not taken for a folder of that name, which
/// "./-" names). Returns 0, or prints why and returns 2 (a usage error).
int cli_check_folder_option(const char* command, const char* option, const char* dir);

/// Checks the file an option writes (NULL: none given) before anything runs: "-" is standard
/// output where `dash_is_stdout`, a file name everywhere else; a file that is `input` itself (the
/// same file under any name), which the command reads and `input_what` names ("the model file"),
/// would be destroyed. Returns 0, or prints why and returns 2 (a usage error).
int cli_check_output(const char* command, const char* option, const char* output, const char* input,
                     const char* input_what, bool dash_is_stdout);

/// Checks, once the model file is loaded into doc, that the file an option writes (NULL or "-":
/// none) is none of the OBJ files its meshes read (sm_document_structure_file_path), which the
/// command would destroy. Returns 0, or prints which mesh reads it and returns 2 (a usage error).
int cli_check_output_not_mesh_file(const char* command, const char* option, const char* output,
                                   const sm_document* doc);

/// Checks that `file`, which the folder option `--vtk dir` writes, is not the model file (the same
/// file under any name), which the command reads and would destroy. Returns 0, or prints why and
/// returns 2 (a usage error).
int cli_check_folder_file(const char* command, const char* dir, const char* file, const char* model);

/// Checks, before anything is computed, that an output can be made where `path` names it (NULL or
/// "-": none): a file in a folder that exists and is no folder, or a `folder` that exists or whose
/// parent does, where this process may write (the file, and the folder that holds it). Returns 0, or prints
/// why not and returns 1, so that a command never stops with some outputs written and others not for a place
/// it could have checked first.
int cli_check_output_place(const char* command, const char* option, const char* path, bool folder);

/// Checks that two outputs (NULL: not given) are not one file under two names, which would leave
/// only the one written last. Returns 0, or prints why and returns 2 (a usage error).
int cli_check_outputs_apart(const char* command, const char* option_a, const char* a, const char* option_b,
                            const char* b);

/// Whether `path` names a file inside `folder` (at any depth, under any names), existing or not.
bool cli_inside(const char* path, const char* folder);

/// Whether paths a and b name one file: the same file under any name if both exist, else the same
/// place once created (the real path of the folder, and the name).
bool cli_same_file(const char* a, const char* b);

/// The sum of the particles' loads [N] into total; returns how many particles have one.
int32_t cli_total_load(const sm_model* model, double total[3]);

/// Removes what an earlier, longer series left behind in the folder of this one: the files
/// prefix<k>extension for k = first, first + 1, ... (k with at least `digits` digits), up to the
/// first that does not exist or is not a regular file of the series (a symbolic link, or a file
/// that does not start with `header`, CLI_LEGACY_VTK_HEADER or CLI_VTP_HEADER, as no model file
/// or CSV does). Returns how many it removed. Nothing guards against another run writing a
/// longer series into the folder at the same time.
long cli_remove_series_tail(const char* prefix, int digits, long first, const char* extension,
                            const char* header);

/// How the files cli_vtk_open writes start.
#define CLI_LEGACY_VTK_HEADER "# vtk DataFile"

/// How the VTK XML polydata files (.vtp) of springmass run's series start.
#define CLI_VTP_HEADER "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\""

/// Prints "springmass COMMAND: cannot write PATH: reason", the reason from errno (set by the
/// failed call just before); nothing for a pipe whose reader has gone while SIGPIPE is held back
/// (cli_hold_pipe_signal), which ends the command once released, quietly as at the write.
void cli_cannot_write(const char* command, const char* path);

/// Closes a file written by a subcommand; prints the error and returns -1 if anything failed.
int cli_close(const char* command, const char* path, FILE* f);
