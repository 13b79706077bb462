# cmake -DEXE=program -DFLAG=--flag -DOUT=file -P write_output.cmake
# Writes what `EXE FLAG` prints to OUT, through a temporary name, so that a
# failed run leaves no half-written file (the build's generated completion).
get_filename_component(_dir ${OUT} DIRECTORY)
file(MAKE_DIRECTORY ${_dir})
execute_process(COMMAND ${EXE} ${FLAG} OUTPUT_FILE ${OUT}.tmp RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  file(REMOVE ${OUT}.tmp)
  message(FATAL_ERROR "${EXE} ${FLAG} failed (${_rc})")
endif()
file(RENAME ${OUT}.tmp ${OUT})
