# Included by the install step (CMakeLists.txt, component dev) with
# ZWIDTH_INCLUDE_ROOT = <DESTDIR><prefix>/include/zwidth: rewrites each
# installed header's includes of the project's modules, "model/error.h", to
# "zwidth/model/error.h", so that <prefix>/include alone is on a consumer's
# path (<zwidth/...>). A header already rewritten is left alone.
file(GLOB_RECURSE _zwidth_headers "${ZWIDTH_INCLUDE_ROOT}/*.h")
foreach(_h IN LISTS _zwidth_headers)
  file(READ "${_h}" _text)
  string(REGEX REPLACE "#include \"(model|ident|fit|stability|io|analysis|report)/" "#include \"zwidth/\\1/"
         _new "${_text}")
  if(NOT _new STREQUAL _text)
    file(WRITE "${_h}" "${_new}")
  endif()
endforeach()
