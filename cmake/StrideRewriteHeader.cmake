# Run by the build (cmake/StrideInstall.cmake) for each header of the <stride/...> view:
#   cmake -DSTRIDE_HEADER_IN=src -DSTRIDE_HEADER_OUT=dst -DSTRIDE_HEADER_LIST=list -P StrideRewriteHeader.cmake
# copies a header, its includes of Stride's headers rewritten from the in-tree short form to the
# public one: "solver/multibody/model.hpp" -> <stride/solver/multibody/model.hpp>,
# "stride/robot_state_t.hpp" (LCM) -> <stride/robot_state_t.hpp>. The list holds the public names
# (one a line, "stride/..."); a quoted include that names none of them is an error: the header
# would not compile for a user (it includes a header that is not installed).
cmake_policy(VERSION 3.25)
file(STRINGS "${STRIDE_HEADER_LIST}" _public)
file(READ "${STRIDE_HEADER_IN}" _text)
string(REGEX MATCHALL "#[ \t]*include[ \t]*\"[^\"]*\"" _directives "${_text}")
foreach(_directive IN LISTS _directives)
  string(REGEX REPLACE "^[^\"]*\"([^\"]*)\"$" "\\1" _path "${_directive}")
  if("stride/${_path}" IN_LIST _public)
    set(_path "stride/${_path}")
  elseif(NOT _path IN_LIST _public)
    message(FATAL_ERROR "${STRIDE_HEADER_IN}: #include \"${_path}\" is not an installed Stride "
                        "header (cmake/StrideInstall.cmake installs the headers a user may include)")
  endif()
  string(REPLACE "${_directive}" "#include <${_path}>" _text "${_text}")
endforeach()
file(WRITE "${STRIDE_HEADER_OUT}" "${_text}")
