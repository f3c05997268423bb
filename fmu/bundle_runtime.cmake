# Assembles the FMU runtime folder: the generic FMU binary and the shared libraries it needs
# (SuiteSparse, jansson and what they pull in), each with RPATH $ORIGIN so that everything
# resolves from binaries/linux64/ of the FMU. Libraries of the C runtime itself (libc, libm,
# libpthread, libdl, librt and the loader) stay those of the machine that loads the FMU, and so
# do the sanitizer runtimes of an instrumented build.
#
# It also gathers the licences of that software: springmass's own (LICENSE, the binary's), and the
# copyright file of the Debian package of each bundled library and of the static archives linked
# into the binary (ARCHIVES, separated by commas), in documentation/licenses/ with a license.txt
# that says which file covers which.
#
#   cmake -DBINARY=<springmass_fmu.so> -DDESTINATION=<dir> -DPATCHELF=<patchelf>
#         -DLICENSE=<springmass's LICENSE> [-DARCHIVES=<a.a>,<b.a>] -P bundle_runtime.cmake
foreach(var BINARY DESTINATION PATCHELF LICENSE)
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
  execute_process(COMMAND "${PATCHELF}" --force-rpath --set-rpath "$ORIGIN" "${file}" RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "bundle_runtime.cmake: patchelf failed on ${file}")
  endif()
endforeach()
list(LENGTH resolved count)
message(STATUS "FMU runtime: springmass_fmu.so and ${count} bundled libraries in ${dir}")

# Licences. Binaries are redistributed with their authors' notices: the Debian copyright file of
# the package that installed each one (dpkg -S), once per package, and license.txt saying which
# covers which. FMI 2.0 keeps documentation in documentation/; FMI 3.0 names
# documentation/licenses/ and its license.txt for exactly this.
set(licenses "${DESTINATION}/documentation/licenses")
file(REMOVE_RECURSE "${DESTINATION}/documentation")
file(MAKE_DIRECTORY "${licenses}")
find_program(DPKG dpkg)
string(REPLACE "," ";" archives "${ARCHIVES}")
file(COPY_FILE "${LICENSE}" "${licenses}/springmass.txt")
set(entry "Licences of the software an FMU made by springmass carries\n\n")
string(APPEND entry "The FMU's binary (binaries/linux64/, named after the model) is springmass, whose licence is\n")
string(APPEND entry "springmass.txt, with the static archives below linked in; the other files of binaries/linux64/\n")
string(APPEND entry "are shared libraries it loads. Each of those came from a Debian package, whose copyright file\n")
string(APPEND entry "(its authors' notices and licences) is in this folder under the package's name.\n\n")
string(APPEND entry "  springmass (the binary)  springmass.txt\n")
set(missing "")
foreach(library IN LISTS archives resolved)
  get_filename_component(name "${library}" NAME)
  file(REAL_PATH "${library}" real)
  # dpkg knows a file by the path its package installed, which on a merged /usr may be the one
  # without the /usr prefix (libgcc_s: /lib/..., found at /usr/lib/...).
  set(package "")
  string(REGEX REPLACE "^/usr/" "/" unmerged "${real}")
  foreach(candidate IN ITEMS "${real}" "${library}" "${unmerged}")
    if(DPKG AND NOT package)
      execute_process(COMMAND "${DPKG}" -S "${candidate}" OUTPUT_VARIABLE owner ERROR_QUIET RESULT_VARIABLE rc)
      if(rc EQUAL 0 AND owner MATCHES "^([^:,]+)")
        set(package "${CMAKE_MATCH_1}")
      endif()
    endif()
  endforeach()
  if(package AND EXISTS "/usr/share/doc/${package}/copyright")
    if(NOT EXISTS "${licenses}/${package}.txt")
      file(COPY_FILE "/usr/share/doc/${package}/copyright" "${licenses}/${package}.txt")
    endif()
    if(name MATCHES "\\.a$")
      string(APPEND entry "  ${name} (linked in)  ${package}.txt\n")
    else()
      string(APPEND entry "  ${name}  ${package}.txt\n")
    endif()
  else()
    list(APPEND missing "${name}")
    string(APPEND entry "  ${name}  (no package found: its licence is not included)\n")
  endif()
endforeach()
file(WRITE "${licenses}/license.txt" "${entry}")
if(missing)
  message(WARNING "bundle_runtime.cmake: no licence found for ${missing} (not installed from a Debian package)")
endif()
