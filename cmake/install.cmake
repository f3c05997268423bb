# Installation: headers, the static library, the command-line tool, a CMake package so that C
# programs use springmass with `find_package(springmass REQUIRED)` and
# `target_link_libraries(app PRIVATE springmass::springmass)`, and a pkg-config file for builds
# without CMake.
include(CMakePackageConfigHelpers)

install(TARGETS springmass EXPORT springmassTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/springmass DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# The licence in springmass's own documentation folder: CMAKE_INSTALL_DOCDIR is named after the
# project that first included GNUInstallDirs, which for springmass added with add_subdirectory is
# the project that adds it, whose own LICENSE there would replace springmass's or be replaced.
if(_sm_top_level)
  set(SPRINGMASS_DOCDIR ${CMAKE_INSTALL_DOCDIR})
else()
  set(SPRINGMASS_DOCDIR ${CMAKE_INSTALL_DATAROOTDIR}/doc/springmass)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${SPRINGMASS_DOCDIR})
# The tool (and the FMU runtime, fmu/CMakeLists.txt) come from the optimised configurations only:
# a Debug build installed into the same prefix adds its library (libspringmassd.a) and its
# pkg-config file (springmassd.pc) and leaves the Release tool, runtime and springmass.pc alone.
# A build type other than Debug counts as optimised: "None", with which Debian's packages are
# built (their own compiler flags alone), or a project's own.
set(SPRINGMASS_OPTIMISED_CONFIGURATIONS Release RelWithDebInfo MinSizeRel)
foreach(_config IN LISTS CMAKE_BUILD_TYPE CMAKE_CONFIGURATION_TYPES)
  string(TOLOWER "${_config}" _config_lower)
  if(NOT _config_lower STREQUAL "debug")
    list(APPEND SPRINGMASS_OPTIMISED_CONFIGURATIONS "${_config}")
  endif()
endforeach()
list(REMOVE_DUPLICATES SPRINGMASS_OPTIMISED_CONFIGURATIONS)
# As install()'s argument: the configurations, or, for a build without a build type (springmass
# added with add_subdirectory to a project that sets none), no restriction, which is the only way
# to name that build's one configuration.
get_property(_multi_config GLOBAL PROPERTY GENERATOR_IS_MULTI_CONFIG)
if(NOT _multi_config AND NOT CMAKE_BUILD_TYPE)
  set(SPRINGMASS_OPTIMISED_ONLY "")
else()
  set(SPRINGMASS_OPTIMISED_ONLY CONFIGURATIONS ${SPRINGMASS_OPTIMISED_CONFIGURATIONS})
endif()
install(TARGETS springmass_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} ${SPRINGMASS_OPTIMISED_ONLY})
# With the tool, what its help refers to and what it runs: the README and docs/ beside the licence
# (`springmass --help` names docs/model-format.md, docs/fmu.md, docs/analysis.md), and the bundled
# models (with the mesh they read) to start from.
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${SPRINGMASS_DOCDIR} ${SPRINGMASS_OPTIMISED_ONLY})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${SPRINGMASS_DOCDIR}/docs ${SPRINGMASS_OPTIMISED_ONLY}
        FILES_MATCHING PATTERN "*.md")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models/ DESTINATION ${CMAKE_INSTALL_DATADIR}/springmass/models
        ${SPRINGMASS_OPTIMISED_ONLY})

set(SPRINGMASS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/springmass)
install(EXPORT springmassTargets NAMESPACE springmass:: DESTINATION ${SPRINGMASS_CMAKE_DIR})
# The package takes the major version of SUNDIALS it was built with, and no later one.
math(EXPR SPRINGMASS_SUNDIALS_NEXT_MAJOR "${SPRINGMASS_SUNDIALS_MAJOR} + 1")
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/springmassConfig.cmake.in
    ${PROJECT_BINARY_DIR}/springmassConfig.cmake INSTALL_DESTINATION ${SPRINGMASS_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/springmassConfigVersion.cmake
    COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/springmassConfig.cmake ${PROJECT_BINARY_DIR}/springmassConfigVersion.cmake
        ${PROJECT_SOURCE_DIR}/cmake/sundials_static.cmake DESTINATION ${SPRINGMASS_CMAKE_DIR})

# pkg-config: the prefix is found from the file's own folder (${pcfiledir}), so that the file
# stays right whatever prefix `cmake --install --prefix` gives. SUNDIALS, KLU and CHOLMOD have no
# pkg-config files on Debian; they are named by library (the shared ones, which pkg-config users
# link by default).
# A library or include folder given as an absolute path (GNUInstallDirs allows it) is written as
# it is, and the file is then not relocatable.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(SPRINGMASS_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
  set(SPRINGMASS_PC_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
else()
  file(RELATIVE_PATH _pc_to_prefix "/root/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/root")
  string(REGEX REPLACE "/$" "" _pc_to_prefix "${_pc_to_prefix}")
  set(SPRINGMASS_PC_PREFIX "\${pcfiledir}/${_pc_to_prefix}")
  set(SPRINGMASS_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(SPRINGMASS_PC_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}")
else()
  set(SPRINGMASS_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
set(SPRINGMASS_PC_LIBS "-lsundials_cvode -lsundials_nvecserial -lsundials_sunmatrixdense")
string(APPEND SPRINGMASS_PC_LIBS " -lsundials_sunmatrixsparse -lsundials_sunlinsoldense -lsundials_sunlinsolklu")
string(APPEND SPRINGMASS_PC_LIBS " -lsundials_sunlinsolpcg")
# SUNDIALS 7 has the parts its libraries share in a library of their own.
if(SPRINGMASS_SUNDIALS_MAJOR GREATER_EQUAL 7)
  string(APPEND SPRINGMASS_PC_LIBS " -lsundials_core")
endif()
# A SUNDIALS outside the linker's own folders (SUNDIALS_DIR, CMAKE_PREFIX_PATH) is named with its
# folder, for the linker and for the loader: the folder of CVODE's library, static or shared,
# whichever the package has (of its first configuration, or without one).
set(_pc_sundials_dir "")
foreach(_pc_target IN ITEMS SUNDIALS::cvode_static SUNDIALS::cvode_shared)
  if(NOT _pc_sundials_dir AND TARGET ${_pc_target})
    get_target_property(_pc_configs ${_pc_target} IMPORTED_CONFIGURATIONS)
    set(_pc_location "")
    if(_pc_configs)
      list(GET _pc_configs 0 _pc_config)
      get_target_property(_pc_location ${_pc_target} IMPORTED_LOCATION_${_pc_config})
    endif()
    if(NOT _pc_location)
      get_target_property(_pc_location ${_pc_target} IMPORTED_LOCATION)
    endif()
    if(_pc_location)
      get_filename_component(_pc_sundials_dir "${_pc_location}" DIRECTORY)
    endif()
  endif()
endforeach()
if(_pc_sundials_dir AND NOT _pc_sundials_dir IN_LIST CMAKE_C_IMPLICIT_LINK_DIRECTORIES)
  string(APPEND SPRINGMASS_PC_LIBS " -L${_pc_sundials_dir} -Wl,-rpath,${_pc_sundials_dir}")
endif()
string(APPEND SPRINGMASS_PC_LIBS " -lklu -lcholmod -ldl -lm")
# The library of this build: libspringmassd in a Debug build (DEBUG_POSTFIX, lib/CMakeLists.txt),
# whatever the case of its name ("debug" too), and for each configuration of a multi-config
# generator: the name comes from the target itself, when the file is generated.
set(SPRINGMASS_PC_LIBRARY "$<TARGET_FILE_BASE_NAME:springmass>")
configure_file(${PROJECT_SOURCE_DIR}/cmake/springmass.pc.in ${PROJECT_BINARY_DIR}/springmass.pc.in @ONLY)
# The file is named after the library: springmassd.pc beside springmass.pc in a shared prefix.
file(GENERATE OUTPUT ${PROJECT_BINARY_DIR}/pkgconfig/$<CONFIG>/$<TARGET_FILE_BASE_NAME:springmass>.pc
     INPUT ${PROJECT_BINARY_DIR}/springmass.pc.in)
install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/$<CONFIG>/$<TARGET_FILE_BASE_NAME:springmass>.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
