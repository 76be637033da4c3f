# FindLCM: the LCM C/C++ library (lcm-proj.github.io). Debian's liblcm-dev ships no CMake package,
# so the header and the library are looked up directly and wrapped in an imported target; Stride's
# build and its installed StrideConfig.cmake both use this file, so the two agree.
#
# Provides LCM::lcm (headers and library), LCM_FOUND, and the cache entries LCM_INCLUDE_DIR and
# LCM_LIBRARY (set them to use another LCM).
find_path(LCM_INCLUDE_DIR lcm/lcm-cpp.hpp)
find_library(LCM_LIBRARY lcm)
mark_as_advanced(LCM_INCLUDE_DIR LCM_LIBRARY)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(LCM REQUIRED_VARS LCM_LIBRARY LCM_INCLUDE_DIR)

if(LCM_FOUND AND NOT TARGET LCM::lcm)
  add_library(LCM::lcm UNKNOWN IMPORTED)
  set_target_properties(LCM::lcm PROPERTIES
    IMPORTED_LOCATION "${LCM_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
endif()
