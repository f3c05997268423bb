# Debian's SUNDIALS 6.4 has two static targets link a shared library: sunlinsoldense_static the
# shared sunmatrixdense, sunlinsolklu_static the shared sunmatrixsparse. Where the linker keeps
# every library it is given (no --as-needed: the sanitizer builds, other compilers or systems),
# the tool, the FMU and every program linking the installed library would then need those shared
# libraries beside the static copies they carry. SUNDIALS 7 has every static target link the
# shared core library (sundials_core), the only core they name: every such program would need it.
# The static targets link their static twins instead. Included after find_package(SUNDIALS) by
# this project's CMakeLists.txt and by the installed package configuration
# (springmassConfig.cmake), whose callers link these targets too.
foreach(_springmass_target IN ITEMS cvode_static nvecserial_static sunmatrixdense_static sunmatrixsparse_static
                                   sunlinsoldense_static sunlinsolklu_static sunlinsolpcg_static)
  if(TARGET SUNDIALS::${_springmass_target})
    get_target_property(_springmass_links SUNDIALS::${_springmass_target} INTERFACE_LINK_LIBRARIES)
    if(_springmass_links)
      string(REGEX REPLACE "(SUNDIALS::[a-z]+)_shared" "\\1_static" _springmass_links "${_springmass_links}")
      set_target_properties(SUNDIALS::${_springmass_target} PROPERTIES
                            INTERFACE_LINK_LIBRARIES "${_springmass_links}")
    endif()
  endif()
endforeach()
unset(_springmass_target)
unset(_springmass_links)
