!> Numbers as text for messages, the log and text outputs: one place, so every message and file
!> formats a value the same way.
module text_format
  use agglo_kinds, only: wp, i8
  implicit none
  private
  public :: real_text, exact_real_text, int_text

  !> An integer (default or 64-bit) without blanks.
  interface int_text
    module procedure int_text_default, int_text_long
  end interface int_text

contains

  !> A real with 6 significant digits, no blanks ("1.00000E-03"): messages and the log.
  function real_text(value) result(text)
    real(wp), intent(in) :: value
    character(len=:), allocatable :: text
    character(len=32) :: buffer
    if (value /= 0.0_wp .and. (abs(value) >= 1.0e100_wp .or. abs(value) < 1.0e-99_wp)) then
      write(buffer, '(es13.5e3)') value     ! three exponent digits keep their "E"
    else
      write(buffer, '(es12.5)') value
    end if
    text = trim(adjustl(buffer))
  end function real_text

  !> A real with 17 significant digits (a double survives the round trip through the text), no blanks.
  function exact_real_text(value) result(text)
    real(wp), intent(in) :: value
    character(len=:), allocatable :: text
    character(len=32) :: buffer
    write(buffer, '(es25.17e3)') value
    text = trim(adjustl(buffer))
  end function exact_real_text

  pure function int_text_default(value) result(text)
    integer, intent(in) :: value
    character(len=:), allocatable :: text
    character(len=16) :: buffer
    write(buffer, '(i0)') value
    text = trim(buffer)
  end function int_text_default

  pure function int_text_long(value) result(text)
    integer(i8), intent(in) :: value
    character(len=:), allocatable :: text
    character(len=24) :: buffer
    write(buffer, '(i0)') value
    text = trim(buffer)
  end function int_text_long
end module text_format
