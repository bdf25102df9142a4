# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# Every floating-point option of every command refuses what is not a finite number, as a usage
# error (exit 2) naming the option and the rule. The options are read from each command's
# --help (the FLOAT ones), so an option added later without a check fails here too: CLI11's own
# Range, PositiveNumber and NonNegativeNumber let "nan" through (`pliant host --duration nan`
# ran until Ctrl-C). Every unsigned option (UINT) refuses a minus sign (CLI11 turned
# `--ticks -5` into 2^64 - 5) and says what else is not a whole number. PLIANT: the executable.
execute_process(COMMAND ${PLIANT} --help RESULT_VARIABLE rc OUTPUT_VARIABLE help ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pliant --help exited ${rc}:\n${help}${err}")
endif()
# The commands: the lines of the SUBCOMMANDS section, "  name   description".
string(FIND "${help}" "SUBCOMMANDS:" at)
if(at EQUAL -1)
    string(FIND "${help}" "Subcommands:" at)
endif()
if(at EQUAL -1)
    message(FATAL_ERROR "no subcommand list in pliant --help:\n${help}")
endif()
string(SUBSTRING "${help}" ${at} -1 section)
string(REGEX MATCHALL "\n  [a-z]+" names "${section}")
set(checked 0)
set(commands 0)
foreach(name IN LISTS names)
    string(STRIP "${name}" command)
    math(EXPR commands "${commands} + 1")
    execute_process(COMMAND ${PLIANT} ${command} --help OUTPUT_VARIABLE usage ERROR_VARIABLE err
                    RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "pliant ${command} --help exited ${rc}:\n${usage}${err}")
    endif()
    foreach(kind FLOAT UINT UINT_TEXT RANGE)
        if(kind STREQUAL "FLOAT")
            set(values nan -nan inf -inf 1e400)
            set(rule "is not a finite number")
            set(shown FLOAT)
        elseif(kind STREQUAL "UINT")
            set(values -5)
            set(rule "is negative")
            set(shown UINT)
        elseif(kind STREQUAL "UINT_TEXT")
            # CLI11 said "Could not convert: --ticks = 1e30".
            set(values 1e30 abc)
            set(rule "is not a (whole number|UDP port)")
            set(shown UINT)
        else()
            # Whole numbers in a range (whole_number_in): CLI11's Range said "Value abc not in
            # range 1 to 10" of text that is no number.
            set(values abc 2.5)
            set(rule "is not a whole number")
            set(shown "INT:INT in \\[")
        endif()
        string(REGEX MATCHALL "\n +(-[a-zA-Z],)?--[a-z0-9-]+ ${shown}" options "${usage}")
        foreach(option IN LISTS options)
            string(REGEX REPLACE ".*(--[a-z0-9-]+) ${shown}" "\\1" option "${option}")
            foreach(value IN LISTS values)
                # 1e400 overflows a double: CLI11 turns it into inf.
                execute_process(COMMAND ${PLIANT} ${command} ${option} ${value}
                                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                                TIMEOUT 20)
                if(NOT rc STREQUAL "2" OR NOT err MATCHES "${option}: ${value} ${rule}")
                    message(FATAL_ERROR
                            "pliant ${command} ${option} ${value}: expected exit 2 and "
                            "'${option}: ${value} ${rule}', got ${rc}:\n${out}${err}")
                endif()
                math(EXPR checked "${checked} + 1")
            endforeach()
        endforeach()
    endforeach()
endforeach()
if(commands LESS 5 OR checked LESS 20)
    message(FATAL_ERROR "found only ${commands} commands and ${checked} cases in the help texts")
endif()
message("${checked} refusals over ${commands} commands")
