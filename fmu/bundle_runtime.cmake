# Assembles the FMU runtime folder: the generic FMU binary and the shared libraries it needs
# (SuiteSparse, jansson and what they pull in), each with RUNPATH $ORIGIN so that everything
# resolves from binaries/linux64/ of the FMU. Libraries of the C runtime itself (libc, libm,
# libpthread, libdl, librt and the loader) stay those of the machine that loads the FMU, and so
# do the sanitizer runtimes of an instrumented build.
#
#   cmake -DBINARY=<springmass_fmu.so> -DDESTINATION=<dir> -DPATCHELF=<patchelf> -P bundle_runtime.cmake
foreach(var BINARY DESTINATION PATCHELF)
  if(NOT ${var})
    message(FATAL_ERROR "bundle_runtime.cmake: ${var} is not set")
  endif()
endforeach()

file(GET_RUNTIME_DEPENDENCIES
  LIBRARIES "${BINARY}"
  RESOLVED_DEPENDENCIES_VAR resolved
  UNRESOLVED_DEPENDENCIES_VAR unresolved
  PRE_EXCLUDE_REGEXES
    "^ld-linux" "^libc\\.so" "^libm\\.so" "^libpthread\\.so" "^libdl\\.so" "^librt\\.so"
    "^libasan\\.so" "^libubsan\\.so" "^liblsan\\.so" "^libtsan\\.so" "^linux-vdso")
if(unresolved)
  message(FATAL_ERROR "bundle_runtime.cmake: cannot resolve ${unresolved} needed by ${BINARY}")
endif()

set(dir "${DESTINATION}/binaries/linux64")
file(REMOVE_RECURSE "${dir}")
file(MAKE_DIRECTORY "${dir}")
set(copied "${dir}/springmass_fmu.so")
file(COPY_FILE "${BINARY}" "${dir}/springmass_fmu.so")
foreach(library IN LISTS resolved)
  # Keep the name the binaries ask for (the soname), with the content of the real file.
  get_filename_component(name "${library}" NAME)
  file(REAL_PATH "${library}" real)
  file(COPY_FILE "${real}" "${dir}/${name}")
  list(APPEND copied "${dir}/${name}")
endforeach()
foreach(file IN LISTS copied)
  execute_process(COMMAND "${PATCHELF}" --set-rpath "$ORIGIN" "${file}" RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "bundle_runtime.cmake: patchelf failed on ${file}")
  endif()
endforeach()
list(LENGTH resolved count)
message(STATUS "FMU runtime: springmass_fmu.so and ${count} bundled libraries in ${dir}")
