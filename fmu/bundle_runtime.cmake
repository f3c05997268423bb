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

# BLAS and LAPACK (CHOLMOD's): the reference implementations (Debian's libblas3 and liblapack3,
# blas/ and lapack/ beside the libraries the alternatives select) rather than OpenBLAS when the
# machine has both. OpenBLAS starts a thread per core in the importer's process as soon as the FMU
# is loaded (every FMU that carries it), whose waiting spins, and weighs 37 MB of the 51 MB
# unpacked. The default solver does not notice (the benchmark cloth, n = 64 and 128:
# the same time within the noise); the cholmod solver's large factorisations take about twice as
# long (n = 32 and 64). Both provide the same sonames.
set(reference_libraries "")
foreach(library IN LISTS resolved)
  get_filename_component(name "${library}" NAME)
  get_filename_component(folder "${library}" DIRECTORY)
  foreach(kind blas lapack)
    if(name STREQUAL "lib${kind}.so.3" AND EXISTS "${folder}/${kind}/${name}")
      list(APPEND reference_libraries "${folder}/${kind}/${name}")
    endif()
  endforeach()
endforeach()
list(LENGTH reference_libraries reference_count)
if(reference_count EQUAL 2)
  list(FILTER resolved EXCLUDE REGEX "/lib(blas|lapack)\\.so\\.3$|/libopenblas[^/]*$")
  file(GET_RUNTIME_DEPENDENCIES
    LIBRARIES ${reference_libraries}
    RESOLVED_DEPENDENCIES_VAR reference_needs
    PRE_EXCLUDE_REGEXES
      "^ld-linux" "^libc\\.so" "^libm\\.so" "^libpthread\\.so" "^libdl\\.so" "^librt\\.so" "^linux-vdso"
      "^libblas\\.so")
  list(APPEND resolved ${reference_libraries} ${reference_needs})
  list(REMOVE_DUPLICATES resolved)
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
