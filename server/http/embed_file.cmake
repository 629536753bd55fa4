# Writes OUT, a C++ file defining `std::string_view NAME()` that returns the bytes of IN
# (the dashboard page compiled in: robodiffd serves it with no file beside it).
# cmake -DIN=file -DOUT=file.cpp -DNAME=function -DNAMESPACE=ns -P embed_file.cmake
file(READ "${IN}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," bytes "${hex}")
string(REGEX REPLACE "(('\\\\x[0-9a-f][0-9a-f]',){32})" "\\1\n    " bytes "${bytes}")
get_filename_component(source_name "${IN}" NAME)
file(WRITE "${OUT}.tmp"
"// Generated from ${source_name} by embed_file.cmake at build time; do not edit.\n"
"#include <string_view>\n\n"
"namespace ${NAMESPACE} {\n\n"
"static const char kBytes[] = {\n    ${bytes}'\\0'};\n\n"
"std::string_view ${NAME}() { return {kBytes, ${size}}; }\n\n"
"}  // namespace ${NAMESPACE}\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
