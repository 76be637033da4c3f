# FindTinyXML: TinyXML 2.6 (libtinyxml-dev), the XML library urdfdom uses and our SRDF reader too.
# It has no CMake package on Debian; used by Stride's build and by its installed StrideConfig.cmake
# (the static libraries link it).
#
# Provides TinyXML::TinyXML, TinyXML_FOUND, and the cache entries TINYXML_INCLUDE_DIR and
# TINYXML_LIBRARY.
find_path(TINYXML_INCLUDE_DIR tinyxml.h)
find_library(TINYXML_LIBRARY tinyxml)
mark_as_advanced(TINYXML_INCLUDE_DIR TINYXML_LIBRARY)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(TinyXML REQUIRED_VARS TINYXML_LIBRARY TINYXML_INCLUDE_DIR)

if(TinyXML_FOUND AND NOT TARGET TinyXML::TinyXML)
  add_library(TinyXML::TinyXML UNKNOWN IMPORTED)
  # Debian's TinyXML is built with STL support; every user of its headers must agree (the class
  # layouts differ without it).
  set_target_properties(TinyXML::TinyXML PROPERTIES
    IMPORTED_LOCATION "${TINYXML_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TINYXML_INCLUDE_DIR}"
    INTERFACE_COMPILE_DEFINITIONS TIXML_USE_STL)
endif()
