! checks: 16
!> Unit tests of the run log's header text: the deck echo without namelist padding, the compiler
!> options summarised and wrapped. Reference: the lines gfortran's namelist output writes (padded
!> character values, blanks around numbers), compacted by hand.
program test_run_header
  use run_header, only: compact_namelist_line, compiler_options_summary, wrap_words
  use test_framework, only: test_start, test_finish, check
  implicit none
  character(len=:), allocatable :: lines(:), summary
  character(len=*), parameter :: options = '-I build/mod -I /usr/include -march=znver3 -mmmx -mavx2 -mfma ' // &
      '-mno-xop -mavx512f --param=l1-cache-size=32 -mtune=znver3 -O3 -fwrapv -J build/mod ' // &
      '-fpre-include=/usr/include/finclude/math-vector-fortran.h'

  call test_start('run_header')
  call expect(' NAME="decaying_box                                  ",', ' NAME="decaying_box",', 'string_padding_trimmed')
  call expect(' SEED=20250224   ,', ' SEED=20250224,', 'blanks_before_comma_dropped')
  call expect(' END_TIME=  4.0000000000000001E-002,', ' END_TIME=4.0000000000000001E-002,', 'blanks_after_equals_dropped')
  call expect(' AXIS1=  1.0000000000000000     ,  0.0000000000000000     ,', &
              ' AXIS1=1.0000000000000000, 0.0000000000000000,', 'array_items_one_blank_apart')
  call expect(' DIRECTORY="out  ""a""  b/   ",', ' DIRECTORY="out  ""a""  b/",', 'inner_blanks_and_doubled_quotes_kept')
  call expect(' DIRECTORY="            ",', ' DIRECTORY="",', 'blank_value_becomes_empty')
  call expect(" INIT='random   ', FILE='a,b  c  ',", " INIT='random', FILE='a,b  c',", 'apostrophe_values')
  call expect('! Deck file: my  deck''s.nml   ', '! Deck file: my  deck''s.nml', 'comment_line_copied')
  call expect('&RUN', '&RUN', 'group_line_unchanged')
  call expect(' /', ' /', 'group_end_unchanged')
  call expect('', '', 'empty_line')

  summary = compiler_options_summary(options)
  call check(summary == '-march=znver3 -mtune=znver3 -O3 -fwrapv (6 instruction-set and cache switches; ' // &
             'vectors: avx2 fma avx512f)', 'options_summary_drops_paths_counts_switches', summary)
  call check(compiler_options_summary('-O0 -g') == '-O0 -g', 'options_summary_plain_options_kept')

  lines = wrap_words('aaa bbb ccc dddddddddd e', 7)
  call check(size(lines) == 4, 'wrap_line_count')
  if (size(lines) == 4) call check(lines(1) == 'aaa bbb' .and. lines(2) == 'ccc' .and. lines(3) == 'dddddddddd' &
                                   .and. lines(4) == 'e', 'wrap_at_blanks_long_word_alone')
  lines = wrap_words(options, 60)
  call check(maxval(len_trim(lines)) <= 60 .and. size(lines) > 1, 'wrap_within_width')
  call test_finish()

contains

  subroutine expect(line, expected, name)
    character(len=*), intent(in) :: line, expected, name
    character(len=:), allocatable :: got
    got = compact_namelist_line(line)
    call check(got == expected .and. len(got) == len(expected), name, '['//got//']')
  end subroutine expect
end program test_run_header
