! checks: 7
!> Tests of text_format: the exact texts of messages and files (fixed Fortran edit descriptors:
!> ES12.5, ES13.5E3 beyond two exponent digits, ES25.17E3, I0).
program test_text_format
  use agglo_kinds, only: wp
  use text_format, only: real_text, exact_real_text, int_text
  use test_framework, only: test_start, test_finish, check
  implicit none
  real(wp) :: value, read_back
  character(len=:), allocatable :: text

  call test_start('text_format')
  call check(real_text(1.0e-3_wp) == '1.00000E-03', 'real_text_six_digits', real_text(1.0e-3_wp))
  call check(real_text(-2.5_wp) == '-2.50000E+00', 'real_text_negative', real_text(-2.5_wp))
  call check(real_text(0.0_wp) == '0.00000E+00', 'real_text_zero', real_text(0.0_wp))
  call check(real_text(1.0e-120_wp) == '1.00000E-120', 'real_text_three_exponent_digits', real_text(1.0e-120_wp))
  call check(int_text(-42) == '-42', 'int_text_no_blanks', int_text(-42))
  call check(int_text(0) == '0', 'int_text_zero', int_text(0))
  ! exact_real_text round-trips a double (a value stored and read back may be compared exactly).
  value = 1.0_wp / 3.0_wp
  text = exact_real_text(value)
  read(text, *) read_back
  call check(read_back == value .and. index(text, ' ') == 0, 'exact_real_text_round_trip', text)
  call test_finish()
end program test_text_format
