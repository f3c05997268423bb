// Whole text files read at once: the FMU runtime's model file, the files `springmass fmu` packs
// and the input signals of `springmass run --input`.
#pragma once

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Files larger than this are refused: the model-file loader's limit (model_file.h) [bytes].
#define TEXT_FILE_MAX_BYTES ((long long)1 << 30)

/// Reads a whole regular file of at most TEXT_FILE_MAX_BYTES into a malloc'ed NUL-terminated
/// buffer and its length (without the NUL). On failure returns NULL with errno set and, if problem
/// is not NULL, *problem saying why in a few words (a static string): the system's reason, or that
/// the path names a directory or other non-regular file (a FIFO, which is refused at once rather
/// than waited on; a device such as /dev/zero) or too large a file.
char* text_file_read(const char* path, size_t* length, const char** problem);

#ifdef __cplusplus
}
#endif
