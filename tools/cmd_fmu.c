// springmass fmu: packages a model file as an FMI 2.0 Co-Simulation FMU.
//
// The FMU is a zip archive of
//   modelDescription.xml                       written from the FMU's variable table
//   binaries/linux64/<modelIdentifier>.so      the generic FMU binary
//   binaries/linux64/lib*.so*                  the shared libraries it needs (RPATH $ORIGIN)
//   resources/model.json                       the model file, byte for byte (a model whose meshes
//                                              read OBJ files: its JSON with their vertices and
//                                              triangles inline, sm_document_to_self_contained_json)
//   resources/parameters.txt                   the values of --set that differ from the file's, if any
//                                              (the GUID hashes this file and model.json together)
//   resources/reference.csv                    a reference result, when one is given
//   documentation/index.html                   the model's variables and how the FMU steps
//   documentation/licenses/                    the licences of the libraries in binaries/
// The binary, its libraries and their licences come from the FMU runtime folder the build
// assembles (<build>/fmu/runtime, installed as <prefix>/<libdir>/springmass/fmu).
#define _XOPEN_SOURCE 700
#include "commands.h"

#include <stdio.h>
#include <string.h>

#ifndef SPRINGMASS_HAVE_FMU

int sm_cmd_fmu(int argc, char** argv)
{
	(void)argc;
	fprintf(stderr,
	        "springmass %s: this build has no FMU support (configure with SPRINGMASS_BUILD_FMU=ON and "
	        "SPRINGMASS_PYTHON set)\n",
	        argv[0]);
	return 1;  // not a usage error: the command cannot run in this build
}

#else

#include "cli_common.h"
#include "cli_signals.h"
#include "fmu_model.h"
#include "fmu_reference.h"
#include "text_file.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <limits.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static void usage(FILE* out)
{
	fprintf(out,
	        "usage: springmass fmu MODEL -o NAME.fmu [--set NAME=VALUE ...] [--reference RESULT.csv]\n"
	        "                      [--runtime DIR]\n"
	        "\n"
	        "Packages the model file MODEL as a self-contained FMI 2.0 Co-Simulation FMU.\n"
	        "Parameters of the file become FMU parameters, ports become inputs and outputs; see\n"
	        "docs/fmu.md for the variables. The vertices and triangles of a mesh read from an OBJ\n"
	        "file (\"file\", found beside MODEL) go in written inline: the FMU needs no OBJ file.\n"
	        "\n"
	        "options:\n"
	        "  -o, --output FILE    the FMU to write (required)\n"
	        "  --set NAME=VALUE     packages the model as if the file gave parameter NAME this value\n"
	        "                       (repeatable): it is the parameter's start value and, for a parameter\n"
	        "                       that sets the structure (a rope's segment count), the FMU's constant.\n"
	        "                       The file goes into the FMU as it is, the values beside it in\n"
	        "                       resources/parameters.txt; the GUID hashes both\n"
	        "  --reference FILE     a reference result to include as resources/reference.csv: a CSV as\n"
	        "                       fmpy writes and reads one, \"time\" and then variables of the FMU as\n"
	        "                       its columns, a row of decimal numbers per time (checked, then packed\n"
	        "                       as it is)\n"
	        "  --runtime DIR        folder holding binaries/linux64/springmass_fmu.so and its libraries\n"
	        "                       (default: $SPRINGMASS_FMU_RUNTIME if set, else the one of this\n"
	        "                       installation or build)\n"
	        "  -h, --help           this text\n"
	        "\n"
	        "Exit status: 0 success, 1 for a bad model, a reference that cannot be read or is no such\n"
	        "result, a missing runtime or an FMU that cannot be written, 2 for a usage error (a\n"
	        "malformed --set, an output that would overwrite an input or go into the runtime, a\n"
	        "SOURCE_DATE_EPOCH that is not a count of seconds).\n");
}

static bool write_all(const char* path, const char* data, size_t length)
{
	FILE* f = fopen(path, "wb");
	if (!f)
		return false;
	bool ok = fwrite(data, 1, length, f) == length;
	ok = (fclose(f) == 0) && ok;
	return ok;
}

// The file that path names once its links are followed (a chain of at most 40, as the kernel
// allows), written to target; the last one names no file yet. False with errno on failure
// (ELOOP for a longer chain or a cycle).
static bool link_target(const char* path, char* target)
{
	if (snprintf(target, PATH_MAX, "%s", path) >= PATH_MAX) {
		errno = ENAMETOOLONG;
		return false;
	}
	for (int depth = 0; depth <= 40; ++depth) {
		struct stat st;
		if (lstat(target, &st) != 0 || !S_ISLNK(st.st_mode))
			return true;
		char link[PATH_MAX];
		const ssize_t n = readlink(target, link, sizeof link - 1);
		if (n < 0)
			return false;
		link[n] = '\0';
		// A relative link is relative to the folder of the link.
		const char* slash = strrchr(target, '/');
		const int folder = link[0] == '/' || !slash ? 0 : (int)(slash - target) + 1;
		char next[PATH_MAX];
		if (snprintf(next, sizeof next, "%.*s%s", folder, target, link) >= (int)sizeof next) {
			errno = ENAMETOOLONG;
			return false;
		}
		memcpy(target, next, sizeof next);
	}
	errno = ELOOP;
	return false;
}

// Writes data to the output. A regular file, or a new one, is written beside it under a
// temporary name that then replaces it, so that a failed write (a full disk) leaves no partial
// archive and an earlier output as it was; the file keeps the earlier one's permissions, or gets
// 0666 less the umask like any new file. A write-protected file is refused as fopen would refuse
// it. A link is followed to the file it names, as fopen follows it, also a link to no file yet:
// the file it names is created the same way. Anything else is only opened for writing, never
// removed: a device is written (/dev/full fails with 'No space left on device'), a directory
// fails with 'Is a directory'.
static bool write_output(const char* output, const char* data, size_t length)
{
	struct stat st;
	char target[PATH_MAX];
	const bool exists = stat(output, &st) == 0;
	if (exists && !S_ISREG(st.st_mode))
		return write_all(output, data, length);
	if (exists && (access(output, W_OK) != 0 || !realpath(output, target)))
		return false;
	if (!exists && !link_target(output, target))
		return errno == ELOOP ? write_all(output, data, length) : false;  // fopen names the loop
	// The temporary name is short, so that an output whose name is as long as the file system
	// allows (255 bytes) has one beside it too.
	const char* slash = strrchr(target, '/');
	const int folder = slash ? (int)(slash - target) + 1 : 0;
	char temporary[PATH_MAX];
	if (snprintf(temporary, sizeof temporary, "%.*sspringmass-fmu.partial-%ld", folder, target,
	             (long)getpid()) >= (int)sizeof temporary) {
		errno = ENAMETOOLONG;
		return false;
	}
	const int fd = open(temporary, O_WRONLY | O_CREAT | O_EXCL, 0666);
	if (fd < 0)
		return false;
	FILE* f = fdopen(fd, "wb");
	if (!f) {
		close(fd);
		unlink(temporary);
		return false;
	}
	bool ok = fwrite(data, 1, length, f) == length && fflush(f) == 0;
	ok = ok && (!exists || fchmod(fd, st.st_mode & 07777) == 0);
	ok = (fclose(f) == 0) && ok;
	ok = ok && rename(temporary, target) == 0;
	if (!ok) {
		const int error = errno;
		unlink(temporary);
		errno = error;
	}
	return ok;
}

// Copies a regular file with its mode; false on failure, with problem (of `size` bytes) saying
// which file could not be read or written, and why.
static bool copy_file(const char* from, const char* to, char* problem, size_t size)
{
	size_t length = 0;
	const char* why = NULL;
	char* data = text_file_read(from, &length, &why);
	if (!data) {
		snprintf(problem, size, "cannot read %s: %s", from, why);
		return false;
	}
	errno = 0;
	bool ok = write_all(to, data, length);
	if (!ok)
		snprintf(problem, size, "cannot write %s: %s", to, errno != 0 ? strerror(errno) : "write error");
	free(data);
	if (ok) {
		struct stat st;
		if (stat(from, &st) == 0)
			chmod(to, st.st_mode & 0777);
	}
	return ok;
}

// out = a + "/" + b; false (and a message) if it does not fit.
static bool join(char* out, size_t size, const char* a, const char* b)
{
	int n = snprintf(out, size, "%s/%s", a, b);
	if (n < 0 || (size_t)n >= size) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: path too long: %s/%s\n", cli_shown_path(&shown, a),
		        cli_shown_path(&shown, b));
		cli_shown_free(&shown);
		return false;
	}
	return true;
}

// Says that the folder at path could not be made, the reason from errno.
static void cannot_create(const char* path)
{
	const char* reason = strerror(errno);
	cli_shown shown = {0};
	fprintf(stderr, "springmass fmu: cannot create %s: %s\n", cli_shown_path(&shown, path), reason);
	cli_shown_free(&shown);
}

static bool is_file(const char* path)
{
	struct stat st;
	return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static bool has_runtime(const char* dir)
{
	char path[PATH_MAX];
	return join(path, sizeof path, dir, "binaries/linux64/springmass_fmu.so") && is_file(path);
}

// The runtime folder: the option, then SPRINGMASS_FMU_RUNTIME, then the installed one beside
// this executable, then, for the tool in the build tree, the one the build assembled beside it.
// Both are found relative to this executable, so that an installed tool never reads the build
// tree it came from (whose runtime may since have been rebuilt, or removed) and names no path of
// it. When none is found, dir holds the installed one's place, for the message.
static bool find_runtime(const char* option, char* dir, size_t size)
{
	if (option) {
		snprintf(dir, size, "%s", option);
		return has_runtime(dir);
	}
	const char* env = getenv("SPRINGMASS_FMU_RUNTIME");
	if (env && *env) {
		snprintf(dir, size, "%s", env);
		return has_runtime(dir);
	}
	// The message names the installed runtime's place (relative to the tool's folder if that is
	// not known).
	snprintf(dir, size, "%s", SPRINGMASS_FMU_RUNTIME_FROM_BIN);
	char exe[PATH_MAX];
	ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
	if (n <= 0)
		return false;
	exe[n] = '\0';
	char* slash = strrchr(exe, '/');
	if (!slash)
		return false;
	*slash = '\0';
	if (!join(dir, size, exe, SPRINGMASS_FMU_RUNTIME_FROM_BIN))
		return false;
	if (has_runtime(dir))
		return true;
	char build[PATH_MAX];
	if (join(build, sizeof build, exe, SPRINGMASS_FMU_RUNTIME_FROM_BUILD_BIN) && has_runtime(build)) {
		snprintf(dir, size, "%s", build);
		return true;
	}
	return false;
}

// A packaging stopped from outside (Ctrl-C, a kill, the terminal closed; cli_signals.h) removes
// its staging folder, which holds a copy of the whole runtime, and writes no FMU: it stops after
// the step it is taking (zip, which gets the terminal's Ctrl-C too, ends at once) and cleans up.

static int remove_entry(const char* path, const struct stat* st, int flag, struct FTW* ftw)
{
	(void)st;
	(void)flag;
	(void)ftw;
	return remove(path);
}

// Runs argv in the folder dir, in UTC (zip writes its entries' times as local times), and waits
// for it; returns its exit status (127 when it could not be started, as a shell has it; 128 + the
// signal that ended it), or -1 when it could not be run or waited for.
static int run_in(const char* dir, char* const argv[])
{
	pid_t pid = fork();
	if (pid < 0)
		return -1;
	if (pid == 0) {
		if (chdir(dir) != 0 || setenv("TZ", "UTC0", 1) != 0)
			_exit(127);
		execvp(argv[0], argv);
		_exit(127);
	}
	int status = 0;
	while (waitpid(pid, &status, 0) < 0) {
		if (errno != EINTR)
			return -1;
	}
	return WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

// Copies every regular file of the folder `from` into the folder `to` (both exist), the file
// named `rename_from` (or none: NULL) under the name `rename_to`. False on failure, with problem
// (of `size` bytes) naming the file or folder that could not be read or written, and why.
static bool copy_folder(const char* from, const char* to, const char* rename_from, const char* rename_to,
                        char* problem, size_t size)
{
	DIR* d = opendir(from);
	if (!d) {
		snprintf(problem, size, "cannot read %s: %s", from, strerror(errno));
		return false;
	}
	struct dirent* entry;
	bool copied = true;
	while (copied && (entry = readdir(d)) != NULL) {
		if (entry->d_name[0] == '.')
			continue;
		char source[PATH_MAX], target[PATH_MAX];
		const bool renamed = rename_from != NULL && strcmp(entry->d_name, rename_from) == 0;
		copied = join(source, sizeof source, from, entry->d_name) &&
		         (!is_file(source) || (join(target, sizeof target, to, renamed ? rename_to : entry->d_name) &&
		                               copy_file(source, target, problem, size)));
		if (!copied && problem[0] == '\0')
			snprintf(problem, size, "a path too long in %s", to);
	}
	closedir(d);
	return copied;
}

// The archive's entries, so that the same inputs give the same bytes whoever packs them and
// when (reproducible builds): every staged folder and file in name order, with the mode 0755
// (folders, and files with an execute bit) or 0644, and the time of archive_time.
typedef struct entry_list {
	char** names;
	size_t count, capacity;
} entry_list;

// Appends name, or with NULL ends the list with a NULL (not counted), as execvp takes it.
static bool add_entry(entry_list* list, const char* name)
{
	if (list->count == list->capacity) {
		const size_t capacity = 2 * list->capacity + 16;
		char** names = realloc(list->names, capacity * sizeof *names);
		if (!names)
			return false;
		list->names = names;
		list->capacity = capacity;
	}
	list->names[list->count] = name ? strdup(name) : NULL;
	return name == NULL || list->names[list->count++] != NULL;
}

static void free_entries(entry_list* list)
{
	for (size_t i = 0; i < list->count; ++i)
		free(list->names[i]);
	free(list->names);
}

// The entries' time: SOURCE_DATE_EPOCH, a decimal count of seconds since 1970 (the
// reproducible-builds convention), within what a zip entry's date holds, 1980-01-01 00:00 to
// 2107-12-31 23:59:58 UTC (earlier times are the first, later ones the last: zip would wrap them
// to 1980); without it (or empty) the first. False, with a message, for a value that is no such
// count, which the convention asks a build to refuse.
static bool archive_time(struct timespec* when)
{
	const time_t earliest = 315532800, latest = (time_t)4354819198LL;
	*when = (struct timespec){earliest, 0};
	const char* epoch = getenv("SOURCE_DATE_EPOCH");
	if (epoch == NULL || *epoch == '\0')
		return true;
	char* end = NULL;
	const long long seconds = strtoll(epoch, &end, 10);  // beyond the range: LLONG_MAX, the last
	if (*epoch < '0' || *epoch > '9' || *end != '\0') {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: SOURCE_DATE_EPOCH '%s' is not a count of seconds since 1970\n",
		        cli_shown_text(&shown, epoch));
		cli_shown_free(&shown);
		return false;
	}
	when->tv_sec = seconds < earliest ? earliest : seconds > latest ? latest : (time_t)seconds;
	return true;
}

// Adds the entries under the staged folder `relative` ("" for the staging folder itself) to list,
// setting their modes and times. False on failure, with errno.
static bool stage_entries(const char* staging, const char* relative, const struct timespec when[2],
                          entry_list* list)
{
	char folder[PATH_MAX];
	if (!join(folder, sizeof folder, staging, relative))
		return false;
	struct dirent** names = NULL;
	const int n = scandir(folder, &names, NULL, alphasort);
	if (n < 0)
		return false;
	bool ok = true;
	for (int i = 0; i < n; ++i) {
		const char* name = names[i]->d_name;
		char entry[PATH_MAX], full[PATH_MAX];
		struct stat st;
		if (ok && name[0] != '.') {
			const int length =
			    snprintf(entry, sizeof entry, "%s%s%s", relative, relative[0] ? "/" : "", name);
			ok = length > 0 && (size_t)length < sizeof entry && join(full, sizeof full, staging, entry) &&
			     stat(full, &st) == 0 && add_entry(list, entry);
			const bool folder_entry = ok && S_ISDIR(st.st_mode);
			ok = ok && chmod(full, folder_entry || (st.st_mode & 0111) ? 0755 : 0644) == 0;
			ok = ok && (!folder_entry || stage_entries(staging, entry, when, list));
			ok = ok && utimensat(AT_FDCWD, full, when, 0) == 0;
		}
		free(names[i]);
	}
	free(names);
	return ok;
}

typedef struct options {
	const char* model;
	const char* output;
	const char* reference;
	const char* runtime;
	const char** sets;  // the values of --set, in order
	int set_count;
} options;

// The parameters of the --set options in the order they were set, each once: where last set
// (last) or where first set. An order with each parameter once is all parameters.txt can hold;
// the two are the same when each is set once, and *repeated says whether one was set again.
// order and seen have room for every parameter of doc. Returns the count.
static int32_t set_order(const options* opt, const sm_document* doc, bool last, int32_t* order, bool* seen,
                         bool* repeated)
{
	memset(seen, 0, ((size_t)sm_document_parameter_count(doc) + 1) * sizeof *seen);
	int32_t count = 0;
	for (int j = 0; j < opt->set_count; ++j) {
		const int32_t i = cli_setting_parameter(doc, opt->sets[last ? opt->set_count - 1 - j : j]);
		if (i >= 0 && seen[i])
			*repeated = true;
		else if (i >= 0) {
			seen[i] = true;
			order[count++] = i;
		}
	}
	for (int32_t a = 0, b = count - 1; last && a < b; ++a, --b) {
		const int32_t t = order[a];
		order[a] = order[b];
		order[b] = t;
	}
	return count;
}

// Applies the --set values to doc (parsed from text), as `springmass run --set` does, and makes the
// text of resources/parameters.txt: *parameters NULL when no value differs from the file's, and
// *doc then as it was. Otherwise *doc is replaced by the document the FMU makes of the model file
// and that text. Returns 0 or the exit status, after printing why.
static int apply_sets(const options* opt, const char* text, size_t length, sm_document** doc,
                      char** parameters, size_t* parameters_length)
{
	*parameters = NULL;
	const int status = cli_set_parameters("fmu", *doc, opt->sets, opt->set_count);
	if (status != 0 || opt->set_count == 0)
		return status;
	// For values the file's order cannot take: the parameters in the order of the --set options
	// (set_order), last set and failing that first set, if the model takes them one at a time in
	// that order; failing both, the file's order, which the FMU takes together, as they were set.
	const int32_t np = sm_document_parameter_count(*doc);
	int32_t* order = malloc(((size_t)np + 1) * sizeof *order);
	bool* seen = malloc(((size_t)np + 1) * sizeof *seen);
	if (!order || !seen) {
		free(order);
		free(seen);
		fprintf(stderr, "springmass fmu: out of memory\n");
		return 1;
	}
	sm_error err = {SM_OK, ""};
	bool repeated = false;
	for (int pass = 0; pass < 3 && !*parameters; ++pass) {
		if (pass == 1 && !repeated)
			continue;
		const int32_t order_count = pass < 2 ? set_order(opt, *doc, pass == 0, order, seen, &repeated) : 0;
		*parameters = fmu_parameters_text(*doc, text, length, opt->model, pass < 2 ? order : NULL,
		                                  order_count, parameters_length, &err);
		if (!*parameters && err.status == SM_ERROR_OUT_OF_MEMORY)
			break;
	}
	free(order);
	free(seen);
	if (!*parameters) {
		fprintf(stderr, "springmass fmu: --set: %s\n", err.message);
		return 1;
	}
	if (*parameters_length == 0) {
		free(*parameters);
		*parameters = NULL;
		return 0;
	}
	sm_document_destroy(*doc);
	*doc = fmu_document_parse(text, length, opt->model, *parameters, *parameters_length, &err);
	if (!*doc) {
		fprintf(stderr, "springmass fmu: --set: %s\n", err.message);
		return 1;
	}
	return 0;
}

static int package(const options* opt)
{
	int result = 1;
	char* text = NULL;
	char* parameters = NULL;
	size_t parameters_length = 0;
	char* xml = NULL;
	char* html = NULL;
	char* reference = NULL;
	size_t reference_length = 0;
	sm_document* doc = NULL;
	fmu_table table;
	memset(&table, 0, sizeof table);
	char staging[PATH_MAX] = "";
	bool pipe_held = false;  // SIGPIPE held back while the FMU is written (cli_hold_pipe_signal)
	char path[PATH_MAX], runtime[PATH_MAX];

	if (!find_runtime(opt->runtime, runtime, sizeof runtime)) {
		cli_shown shown = {0};
		fprintf(stderr,
		        "springmass fmu: no FMU runtime (binaries/linux64/springmass_fmu.so) in %s%s; give one with "
		        "--runtime\n",
		        cli_shown_path(&shown, runtime),
		        opt->runtime == NULL && getenv("SPRINGMASS_FMU_RUNTIME") != NULL &&
		                *getenv("SPRINGMASS_FMU_RUNTIME")
		            ? " (from $SPRINGMASS_FMU_RUNTIME)"
					: "");
		cli_shown_free(&shown);
		return 1;
	}
	// The runtime is read as the FMU is packed: no output goes into it (it would replace the binary
	// the next FMU packs, or a licence).
	if (cli_inside(opt->output, runtime)) {
		cli_shown shown = {0};
		fprintf(stderr,
		        "springmass fmu: -o %s is inside the FMU runtime %s, which it reads; give another name\n",
		        cli_shown_path(&shown, opt->output), cli_shown_path(&shown, runtime));
		cli_shown_free(&shown);
		return 2;
	}
	size_t length = 0;
	const char* problem = NULL;
	text = text_file_read(opt->model, &length, &problem);
	if (!text) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: cannot read %s: %s\n", cli_shown_path(&shown, opt->model), problem);
		cli_shown_free(&shown);
		goto done;
	}
	sm_error err = {SM_OK, ""};
	// The OBJ files of its meshes are found beside the model file, as `springmass check` finds them.
	char folder[PATH_MAX] = "";
	const char* slash = strrchr(opt->model, '/');
	if (slash != NULL)
		snprintf(folder, sizeof folder, "%.*s", slash == opt->model ? 1 : (int)(slash - opt->model),
		         opt->model);
	doc = sm_document_parse_in_folder(text, length, opt->model, folder, &err);
	if (!doc) {
		fprintf(stderr, "springmass fmu: %s\n", err.message);
		goto done;
	}
	const int overwrites = cli_check_output_not_mesh_file("fmu", "-o", opt->output, doc);
	if (overwrites != 0) {
		result = overwrites;
		goto done;
	}
	// The FMU carries no OBJ file: a model whose meshes read one packs its text with their vertices
	// and triangles written inline, which loads to the same model without them.
	bool reads_files = false;
	for (int32_t k = 0; k < sm_document_structure_count(doc); ++k)
		reads_files = reads_files || sm_document_structure_file(doc, k) != NULL;
	if (reads_files) {
		char* self_contained = sm_document_to_self_contained_json(doc, &err);
		sm_document_destroy(doc);
		doc = NULL;
		if (!self_contained) {
			fprintf(stderr, "springmass fmu: %s\n", err.message);
			goto done;
		}
		free(text);
		text = self_contained;
		length = strlen(text);
		doc = sm_document_parse(text, length, opt->model, &err);
		if (!doc) {
			cli_shown shown = {0};
			fprintf(stderr, "springmass fmu: %s: its meshes written inline: %s\n",
			        cli_shown_path(&shown, opt->model), err.message);
			cli_shown_free(&shown);
			goto done;
		}
	}
	const int set_status = apply_sets(opt, text, length, &doc, &parameters, &parameters_length);
	if (set_status != 0) {
		result = set_status;
		goto done;
	}
	if (fmu_table_create(doc, text, length, parameters, parameters_length, &table, &err) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: %s: %s\n", cli_shown_path(&shown, opt->model), err.message);
		cli_shown_free(&shown);
		goto done;
	}
	// The FMU starts from the file's tolerances: a model too small for them, or a spring too stiff
	// for its velocity tolerance, is warned about here, as `check` and `run` do, since the FMU's
	// importer has no one to tell.
	sm_model* model = NULL;
	if (sm_document_build(doc, &model, NULL) == SM_OK) {
		const sm_document_settings settings = sm_document_get_settings(doc);
		cli_warn_coarse_tolerances(stderr, "springmass fmu: warning: ", model, &settings.solver);
		cli_warn_tight_tolerances(stderr, "springmass fmu: warning: ", doc, model, &settings.solver);
		sm_model_destroy(model);
	}
	// The reference result names the FMU's variables: checked against them before anything is
	// written, and packed as it was read.
	if (opt->reference) {
		reference = text_file_read(opt->reference, &reference_length, &problem);
		if (!reference) {
			cli_shown shown = {0};
			fprintf(stderr, "springmass fmu: cannot read the reference result %s: %s\n",
			        cli_shown_path(&shown, opt->reference), problem);
			cli_shown_free(&shown);
			goto done;
		}
		bool out_of_memory = false;
		char* wrong = fmu_reference_problem(reference, reference_length, &table, &out_of_memory);
		if (wrong != NULL || out_of_memory) {
			cli_shown shown = {0};
			fprintf(stderr, "springmass fmu: --reference %s:%s\n", cli_shown_path(&shown, opt->reference),
			        wrong != NULL ? wrong : " out of memory");
			cli_shown_free(&shown);
			free(wrong);
			goto done;
		}
	}
	xml = fmu_model_description(&table, NULL);
	if (!xml) {
		fprintf(stderr, "springmass fmu: out of memory\n");
		goto done;
	}

	cli_catch_stop_signals(false);
	const char* tmp = getenv("TMPDIR");
	snprintf(staging, sizeof staging, "%s/springmass-fmu-XXXXXX", tmp && *tmp ? tmp : "/tmp");
	if (!mkdtemp(staging)) {
		const char* reason = strerror(errno);
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: cannot create a staging folder in %s%s: %s\n",
		        tmp && *tmp ? cli_shown_path(&shown, tmp) : "/tmp", tmp && *tmp ? " ($TMPDIR)" : "", reason);
		cli_shown_free(&shown);
		staging[0] = '\0';
		goto done;
	}
	const char* folders[] = {"binaries", "binaries/linux64", "resources"};
	for (size_t i = 0; i < sizeof folders / sizeof folders[0]; ++i) {
		if (!join(path, sizeof path, staging, folders[i]))
			goto done;
		if (mkdir(path, 0755) != 0) {
			cannot_create(path);
			goto done;
		}
	}
	if (!join(path, sizeof path, staging, "modelDescription.xml"))
		goto done;
	if (!write_all(path, xml, strlen(xml)))
		goto write_failed;
	if (!join(path, sizeof path, staging, "resources/model.json"))
		goto done;
	if (!write_all(path, text, length))
		goto write_failed;
	if (parameters) {
		if (!join(path, sizeof path, staging, "resources/" FMU_PARAMETERS_RESOURCE))
			goto done;
		if (!write_all(path, parameters, parameters_length))
			goto write_failed;
	}
	if (opt->reference) {
		if (!join(path, sizeof path, staging, "resources/reference.csv"))
			goto done;
		if (!write_all(path, reference, reference_length))
			goto write_failed;
	}

	// The binary under the model's identifier, every bundled library as it is, and their
	// licences (a runtime assembled before they were gathered has none).
	char binary_name[NAME_MAX + 1], from[PATH_MAX];
	const int written_name = snprintf(binary_name, sizeof binary_name, "%s.so", table.model_identifier);
	if (written_name < 0 || (size_t)written_name >= sizeof binary_name ||
	    !join(from, sizeof from, runtime, "binaries/linux64") ||
	    !join(path, sizeof path, staging, "binaries/linux64"))
		goto done;
	if (cli_stop_signal != 0)
		goto done;
	char problem_text[2 * PATH_MAX + 64] = "";
	if (!copy_folder(from, path, "springmass_fmu.so", binary_name, problem_text, sizeof problem_text)) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: cannot copy the FMU runtime from %s: %s\n",
		        cli_shown_path(&shown, from), cli_shown_path(&shown, problem_text));
		cli_shown_free(&shown);
		goto done;
	}
	// documentation/: the page written from the table and, from the runtime, the licences (a
	// runtime assembled before they were gathered has none).
	if (!join(path, sizeof path, staging, "documentation"))
		goto done;
	if (mkdir(path, 0755) != 0) {
		cannot_create(path);
		goto done;
	}
	if (!join(from, sizeof from, runtime, "documentation/licenses"))
		goto done;
	struct stat info;
	const bool licenses = stat(from, &info) == 0 && S_ISDIR(info.st_mode);
	if (licenses) {
		if (!join(path, sizeof path, staging, "documentation/licenses"))
			goto done;
		if (mkdir(path, 0755) != 0) {
			cannot_create(path);
			goto done;
		}
		if (!copy_folder(from, path, NULL, NULL, problem_text, sizeof problem_text)) {
			cli_shown shown = {0};
			fprintf(stderr, "springmass fmu: cannot copy the licences from %s: %s\n",
			        cli_shown_path(&shown, from), cli_shown_path(&shown, problem_text));
			cli_shown_free(&shown);
			goto done;
		}
	}
	html = fmu_documentation_html(&table, licenses);
	if (!html) {
		fprintf(stderr, "springmass fmu: out of memory\n");
		goto done;
	}
	if (!join(path, sizeof path, staging, "documentation/index.html"))
		goto done;
	if (!write_all(path, html, strlen(html)))
		goto write_failed;

	// zip writes the entries in the order given into the staging folder, under a name with an
	// extension (zip adds ".zip" to one without), and the archive is then copied to the output
	// (see write_output). -X: no owner or extra times, which would differ between packers.
	struct timespec when;
	archive_time(&when);  // checked with the arguments
	const struct timespec times[2] = {when, when};
	entry_list entries = {NULL, 0, 0};
	errno = 0;
	if (!add_entry(&entries, "zip") || !add_entry(&entries, "-q") || !add_entry(&entries, "-X") ||
	    !add_entry(&entries, "model.fmu") || !stage_entries(staging, "", times, &entries) ||
	    !add_entry(&entries, NULL)) {
		const char* reason = errno != 0 ? strerror(errno) : "out of memory";
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: cannot prepare the files to archive in %s: %s\n",
		        cli_shown_path(&shown, staging), reason);
		cli_shown_free(&shown);
		free_entries(&entries);
		goto done;
	}
	const int zip_status = cli_stop_signal == 0 ? run_in(staging, entries.names) : -1;
	free_entries(&entries);
	if (cli_stop_signal != 0 || !join(path, sizeof path, staging, "model.fmu"))
		goto done;
	if (zip_status == 127 || zip_status < 0) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: cannot run zip in %s (is zip installed?)\n",
		        cli_shown_path(&shown, staging));
		cli_shown_free(&shown);
		goto done;
	}
	// zip has said why on stderr (a full disk: 'zip I/O error: No space left on device').
	if (zip_status != 0) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: zip failed to write the archive %s (exit status %d)\n",
		        cli_shown_path(&shown, path), zip_status);
		cli_shown_free(&shown);
		goto done;
	}
	size_t archive_length = 0;
	char* archive = text_file_read(path, &archive_length, &problem);
	if (!archive) {
		fprintf(stderr, "springmass fmu: cannot read the archive zip wrote: %s\n", problem);
		goto done;
	}
	if (cli_stop_signal != 0) {
		free(archive);
		goto done;
	}
	// An output that is a pipe whose reader has gone (-o /dev/stdout) fails the write; the signal
	// ends the command once the staging folder is removed, not before.
	pipe_held = cli_hold_pipe_signal();
	errno = 0;
	const bool written = write_output(opt->output, archive, archive_length);
	free(archive);
	if (!written) {
		cli_cannot_write("fmu", opt->output);
		goto done;
	}
	{
		cli_shown shown = {0};
		printf("springmass fmu: wrote %s (model %s, %d variables, GUID %s)\n",
		       cli_shown_path(&shown, opt->output), table.model_identifier, (int)table.count, table.guid);
		cli_shown_free(&shown);
	}
	if (parameters) {
		printf("springmass fmu: parameter values of resources/" FMU_PARAMETERS_RESOURCE ":");
		for (const char* line = parameters; *line; line = strchr(line, '\n') + 1)
			printf(" %.*s", (int)(strchr(line, '\n') - line), line);
		printf("\n");
	}
	result = 0;
	goto done;

write_failed:
	cli_cannot_write("fmu", path);
done:
	if (staging[0])
		nftw(staging, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
	cli_release_pipe_signal(pipe_held);
	free(xml);
	free(html);
	free(reference);
	fmu_table_destroy(&table);
	sm_document_destroy(doc);
	free(parameters);
	free(text);
	// Stopped by a signal before the FMU was written: the staging folder is gone; the exit status
	// is the signal's. One that came while the FMU was written lets it end as it would have.
	if (cli_stop_signal != 0 && result != 0) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass fmu: stopped by %s; %s not written\n", strsignal(cli_stop_signal),
		        cli_shown_path(&shown, opt->output));
		cli_shown_free(&shown);
		cli_end_by_stop_signal();
	}
	return result;
}

// Reads the arguments into opt: 0 to go on, -1 after printing the help, or the exit status of a
// usage error after printing it.
static int parse_arguments(int argc, char** argv, options* opt)
{
	for (int i = 1; i < argc; ++i) {
		const char* a = argv[i];
		if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
			usage(stdout);
			return -1;
		}
		const bool set = strcmp(a, "--set") == 0;
		const char** slot = NULL;
		if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0)
			slot = &opt->output;
		else if (strcmp(a, "--reference") == 0)
			slot = &opt->reference;
		else if (strcmp(a, "--runtime") == 0)
			slot = &opt->runtime;
		else if (set)
			slot = &opt->sets[opt->set_count];
		if (slot) {
			if (i + 1 >= argc) {
				fprintf(stderr, "springmass fmu: %s needs a value\n\n", a);
				usage(stderr);
				return 2;
			}
			*slot = argv[++i];
			opt->set_count += set;
		} else if (cli_model_argument("fmu", a, &opt->model) != 0) {
			usage(stderr);
			return 2;
		}
	}
	if (cli_model_given("fmu", opt->model) != 0 || !opt->output) {
		if (opt->model)
			fprintf(stderr, "springmass fmu: no output given (-o NAME.fmu)\n\n");
		usage(stderr);
		return 2;
	}
	if (cli_check_output("fmu", "-o", opt->output, opt->model, "the model file", false) != 0 ||
	    cli_check_output("fmu", "-o", opt->output, opt->reference, "the reference", false) != 0)
		return 2;
	struct timespec when;
	return archive_time(&when) ? 0 : 2;
}

int sm_cmd_fmu(int argc, char** argv)
{
	options opt = {NULL, NULL, NULL, NULL, NULL, 0};
	opt.sets = calloc((size_t)argc + 1, sizeof *opt.sets);
	if (!opt.sets) {
		fprintf(stderr, "springmass fmu: out of memory\n");
		return 1;
	}
	const int status = parse_arguments(argc, argv, &opt);
	const int result = status > 0 ? status : status < 0 ? 0 : package(&opt);
	free(opt.sets);
	return result;
}

#endif
