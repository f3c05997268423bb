# Installation: headers, the static library, the command-line tool and a CMake package so that
# C programs use springmass with `find_package(springmass REQUIRED)` and
# `target_link_libraries(app PRIVATE springmass::springmass)`.
include(CMakePackageConfigHelpers)

install(TARGETS springmass EXPORT springmassTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/springmass DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS springmass_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

set(SPRINGMASS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/springmass)
install(EXPORT springmassTargets NAMESPACE springmass:: DESTINATION ${SPRINGMASS_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/springmassConfig.cmake.in
    ${PROJECT_BINARY_DIR}/springmassConfig.cmake INSTALL_DESTINATION ${SPRINGMASS_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/springmassConfigVersion.cmake
    COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/springmassConfig.cmake ${PROJECT_BINARY_DIR}/springmassConfigVersion.cmake
        DESTINATION ${SPRINGMASS_CMAKE_DIR})
