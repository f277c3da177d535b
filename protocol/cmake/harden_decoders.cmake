# Runs after lcm-gen (cmake -P, -DHEADERS=a.hpp|b.hpp). lcm-gen 1.3.1's decoders allocate before
# they check: a string length <= 0 reaches std::string::assign(p, len - 1) (length_error), and an
# array count reaches vector::resize(count) before any bounds check (a count of 1e8 allocates
# gigabytes, a negative one throws). Every string length must be >= 1 (its NUL) and every array
# count must fit in the bytes still unread (each element takes at least one byte), so both are
# checked before anything is allocated. The build fails if lcm-gen's output changes shape.
string(REPLACE "|" ";" headers "${HEADERS}")
foreach(h IN LISTS headers)
  file(READ ${h} text)
  set(before "${text}")
  # strings: if(LEN > maxlen - pos) return -1;  ->  also refuse LEN < 1
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]*len_*) > maxlen - pos\\) return -1;"
         "if(\\1 < 1 || \\1 > maxlen - pos) return -1;" text "${text}")
  # variable arrays: this->X.resize(this->COUNT);  ->  the count first checked against the bytes left
  string(REGEX REPLACE "([ ]*)this->([A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
         "\\1if(this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;\n\\1this->\\2.resize(this->\\3);" text "${text}")
  # every allocation site must now be guarded (';' is CMake's list separator: checked as '@')
  string(REPLACE ";" "@" checked "${text}")
  string(REGEX MATCHALL "[^\n]*\n[^\n]*\\.resize\\(this->[^\n]*" resizes "${checked}")
  foreach(r IN LISTS resizes)
    if(NOT r MATCHES "< 0 \\|\\|")
      message(FATAL_ERROR "harden_decoders: unguarded resize in ${h}:\n${r}")
    endif()
  endforeach()
  string(REGEX MATCHALL "[^\n]*len_* > maxlen - pos\\) return -1@" len_checks "${checked}")
  foreach(c IN LISTS len_checks)
    if(NOT c MATCHES "< 1 \\|\\|")
      message(FATAL_ERROR "harden_decoders: unguarded string length in ${h}:\n${c}")
    endif()
  endforeach()
  string(REGEX MATCHALL "\\.assign\\(" assigns "${checked}")
  list(LENGTH assigns n_assign)
  list(LENGTH len_checks n_len)
  if(NOT n_assign EQUAL n_len)
    message(FATAL_ERROR "harden_decoders: ${h} has ${n_assign} string assigns but ${n_len} length checks: lcm-gen's output changed")
  endif()
  if(NOT text STREQUAL before)
    file(WRITE ${h} "${text}")
  endif()
endforeach()
