!> A small writer of JSON objects (RFC 8259) for Agglo's machine-readable summaries.
!> Build an object key by key, then take its text:
!>   call json_add(object, 'name', 'run1'); call json_add(object, 'steps', 120_i8)
!>   text = json_text(object)
!> Values: strings (escaped), real(wp) (17 significant digits: a double reads back exactly; NaN and
!> infinities, which JSON cannot express, are written as null), integers, logicals, null and nested
!> objects. Keys appear in the order added.
module json_writer
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use agglo_kinds, only: wp, i8
  use text_format, only: int_text
  implicit none
  private
  public :: json_object_t, json_add, json_add_null, json_text, json_string, json_real

  type :: json_member_t
    character(len=:), allocatable :: text    !< "key": value
  end type json_member_t

  type :: json_object_t
    type(json_member_t), allocatable :: members(:)
  end type json_object_t

  interface json_add
    module procedure add_string, add_real, add_int, add_i8, add_logical, add_object
  end interface json_add

contains

  subroutine add_member(object, key, value_text)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key, value_text
    type(json_member_t) :: member
    if (.not. allocated(object%members)) allocate(object%members(0))
    member%text = json_string(key)//': '//value_text
    object%members = [object%members, member]
  end subroutine add_member

  subroutine add_string(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key, value
    call add_member(object, key, json_string(value))
  end subroutine add_string

  subroutine add_real(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    real(wp), intent(in) :: value
    call add_member(object, key, json_real(value))
  end subroutine add_real

  subroutine add_int(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    integer, intent(in) :: value
    call add_i8(object, key, int(value, i8))
  end subroutine add_int

  subroutine add_i8(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    integer(i8), intent(in) :: value
    call add_member(object, key, int_text(value))
  end subroutine add_i8

  subroutine add_logical(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    logical, intent(in) :: value
    call add_member(object, key, merge('true ', 'false', value))
    object%members(size(object%members))%text = trim(object%members(size(object%members))%text)
  end subroutine add_logical

  subroutine add_object(object, key, value)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    type(json_object_t), intent(in) :: value
    call add_member(object, key, json_text(value, indent=2))
  end subroutine add_object

  subroutine json_add_null(object, key)
    type(json_object_t), intent(inout) :: object
    character(len=*), intent(in) :: key
    call add_member(object, key, 'null')
  end subroutine json_add_null

  !> The object as JSON text, one member per line (indent = blanks before nested lines).
  recursive function json_text(object, indent) result(text)
    type(json_object_t), intent(in) :: object
    integer, intent(in), optional :: indent
    character(len=:), allocatable :: text
    character(len=:), allocatable :: pad
    integer :: i
    pad = repeat(' ', 2)
    if (present(indent)) pad = repeat(' ', indent + 2)
    if (.not. allocated(object%members)) then
      text = '{}'
      return
    end if
    if (size(object%members) == 0) then
      text = '{}'
      return
    end if
    text = '{'//new_line('a')
    do i = 1, size(object%members)
      text = text//pad//object%members(i)%text
      if (i < size(object%members)) text = text//','
      text = text//new_line('a')
    end do
    text = text//pad(1:len(pad) - 2)//'}'
  end function json_text

  !> A JSON string literal: quotes, backslashes and control characters escaped.
  function json_string(value) result(text)
    character(len=*), intent(in) :: value
    character(len=:), allocatable :: text
    character(len=6) :: escaped
    integer :: i, code
    text = '"'
    do i = 1, len(value)
      code = iachar(value(i:i))
      select case (code)
      case (34); text = text//'\"'
      case (92); text = text//'\\'
      case (10); text = text//'\n'
      case (13); text = text//'\r'
      case (9); text = text//'\t'
      case (0:8, 11:12, 14:31, 127)
        write(escaped, '(a,z4.4)') '\u', code
        text = text//escaped
      case default; text = text//value(i:i)
      end select
    end do
    text = text//'"'
  end function json_string

  !> A JSON number with 17 significant digits (exact round trip of a double); null if not finite.
  function json_real(value) result(text)
    real(wp), intent(in) :: value
    character(len=:), allocatable :: text
    character(len=32) :: buffer
    if (.not. ieee_is_finite(value)) then
      text = 'null'
      return
    end if
    write(buffer, '(es24.16e3)') value
    text = trim(adjustl(buffer))
  end function json_real
end module json_writer
