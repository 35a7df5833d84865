# Writes OUTPUT, a C++ header holding SCRIPT and STYLE as raw string literals (kViewerScript,
# kViewerStyle): the comparison viewer's code, embedded in penumbra_report at build time.
# Run as: cmake -DSCRIPT=viewer.js -DSTYLE=viewer.css -DOUTPUT=viewer_assets.h -P embed_assets.cmake
set(_delimiter "penumbra_viewer")
set(_text "#pragma once\n// Generated from viewer/ by viewer/embed_assets.cmake; do not edit.\n#include <string_view>\n\nnamespace penumbra {\n")
foreach(_pair "kViewerScript;${SCRIPT}" "kViewerStyle;${STYLE}")
  list(GET _pair 0 _name)
  list(GET _pair 1 _file)
  file(READ "${_file}" _content)
  string(FIND "${_content}" ")${_delimiter}\"" _clash)
  if(NOT _clash EQUAL -1)
    message(FATAL_ERROR "${_file} contains the raw string delimiter )${_delimiter}\"")
  endif()
  string(APPEND _text "inline constexpr std::string_view ${_name} = R\"${_delimiter}(${_content})${_delimiter}\";\n")
endforeach()
string(APPEND _text "\n}  // namespace penumbra\n")
# Rewrite only on change, so that an unchanged asset does not rebuild its users.
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" _old)
  if(_old STREQUAL _text)
    return()
  endif()
endif()
file(WRITE "${OUTPUT}" "${_text}")
