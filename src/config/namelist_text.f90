!> The variables of namelist groups as a namelist WRITE prints them ("&GROUP", " NAME=value,",
!> " /"): one item (group, variable, value text) per variable, in order. Reading a configuration
!> back through its own namelist output lets the checks walk every variable of the deck in one
!> place (no list of variables to keep in step with the groups), and lets a test compare every
!> variable written with the value read back.
module namelist_text
  use agglo_kinds, only: wp
  use deck_file, only: lower
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: namelist_item_t, read_namelist_items, item_is_text, item_text_fills, item_text_values, item_tokens, &
            item_is_finite

  type :: namelist_item_t
    character(len=:), allocatable :: group      !< group name, lower case
    character(len=:), allocatable :: name       !< variable name, lower case
    character(len=:), allocatable :: value      !< value text as written (trailing separators removed)
  end type namelist_item_t

  integer, parameter :: longest_record = 8192   !< longer than any written item (strings are <= 4096)

contains

  !> Every item of the namelist groups written to unit (read from its start).
  subroutine read_namelist_items(unit, items)
    integer, intent(in) :: unit
    type(namelist_item_t), allocatable, intent(out) :: items(:)
    character(len=longest_record) :: record
    character(len=:), allocatable :: group, text
    integer :: ios, eq, n
    allocate(items(0))
    group = ''
    rewind(unit)
    do
      read(unit, '(a)', iostat=ios) record
      if (ios /= 0) exit
      text = trim(adjustl(record))
      if (len(text) == 0) cycle
      if (text(1:1) == '&') then
        group = lower(text(2:))
      else if (text(1:1) == '/') then
        group = ''
      else if (len(group) > 0) then
        eq = name_end(text)
        if (eq > 0) then
          call append_item(items, group, lower(text(1:eq - 1)), text(eq + 1:))
        else if (size(items) > 0) then     ! a value continued on the next record
          n = size(items)
          items(n)%value = items(n)%value//' '//text
        end if
      end if
    end do
    do n = 1, size(items)
      items(n)%value = strip_separators(items(n)%value)
    end do
  end subroutine read_namelist_items

  subroutine append_item(items, group, name, value)
    type(namelist_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: group, name, value
    type(namelist_item_t), allocatable :: grown(:)
    integer :: k
    allocate(grown(size(items) + 1))
    do k = 1, size(items)
      call move_alloc(items(k)%group, grown(k)%group)
      call move_alloc(items(k)%name, grown(k)%name)
      call move_alloc(items(k)%value, grown(k)%value)
    end do
    k = size(grown)
    grown(k)%group = group
    grown(k)%name = name
    grown(k)%value = value
    call move_alloc(grown, items)
  end subroutine append_item

  !> Position of the "=" after a leading variable name (letters, digits, _, %, subscripts), else 0.
  pure integer function name_end(text)
    character(len=*), intent(in) :: text
    integer :: i
    name_end = 0
    if (len(text) == 0) return
    if (scan(text(1:1), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ') == 0) return
    do i = 2, len(text)
      if (text(i:i) == '=') then
        name_end = i
        return
      end if
      if (scan(text(i:i), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_%(), ') == 0) return
    end do
  end function name_end

  pure function strip_separators(text) result(out)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: out
    out = trim(adjustl(text))
    do while (len(out) > 0)
      if (out(len(out):len(out)) /= ',') exit
      out = trim(out(1:len(out) - 1))
    end do
  end function strip_separators

  !> A character value (written between quotes).
  pure logical function item_is_text(item)
    type(namelist_item_t), intent(in) :: item
    integer :: first
    first = verify(item%value, '0123456789*')   ! past a repeat count "r*"
    item_is_text = .false.
    if (first > 0) item_is_text = (item%value(first:first) == '''' .or. item%value(first:first) == '"')
  end function item_is_text

  !> A character item in which some element fills its variable to the last character: the written
  !> text is padded to the variable's length, so a value that reaches the end may have been cut
  !> when read.
  logical function item_text_fills(item)
    type(namelist_item_t), intent(in) :: item
    character(len=:), allocatable :: values(:)
    integer :: k, n
    item_text_fills = .false.
    if (.not. item_is_text(item)) return
    values = item_text_values(item)
    n = len(values)
    if (n == 0) return
    do k = 1, size(values)
      if (values(k)(n:n) /= ' ') item_text_fills = .true.
    end do
  end function item_text_fills

  !> The elements of a character item as written, padding kept ("r*'v'" expanded to r copies; a
  !> doubled quote inside the text is one quote).
  function item_text_values(item) result(values)
    type(namelist_item_t), intent(in) :: item
    character(len=:), allocatable :: values(:)
    character(len=:), allocatable :: text, element
    character(len=1) :: quote
    integer :: i, repeats, star, r, ios, longest
    allocate(character(len=len(item%value)) :: values(0))
    longest = 0
    text = item%value
    i = 1
    do while (i <= len(text))
      if (scan(text(i:i), ' ,') > 0) then
        i = i + 1
        cycle
      end if
      repeats = 1
      star = index(text(i:), '*')
      if (star > 1) then
        if (verify(text(i:i + star - 2), '0123456789') == 0) then
          read(text(i:i + star - 2), *, iostat=ios) repeats
          if (ios /= 0) repeats = 1
          i = i + star
        end if
      end if
      quote = text(i:i)
      element = ''
      i = i + 1
      do while (i <= len(text))
        if (text(i:i) == quote) then
          if (i < len(text)) then
            if (text(i + 1:i + 1) == quote) then
              element = element//quote
              i = i + 2
              cycle
            end if
          end if
          exit
        end if
        element = element//text(i:i)
        i = i + 1
      end do
      i = i + 1
      longest = max(longest, len(element))
      do r = 1, max(repeats, 1)
        values = [character(len=len(item%value)) :: values, element]
      end do
    end do
    values = [character(len=longest) :: values]
  end function item_text_values

  !> The values of a non-character item, one per element ("r*v" repeat counts expanded to r copies).
  function item_tokens(item) result(tokens)
    type(namelist_item_t), intent(in) :: item
    character(len=64), allocatable :: tokens(:)
    integer :: start, i, star, repeats, ios, r
    character(len=:), allocatable :: text, token
    allocate(tokens(0))
    text = item%value//','
    start = 1
    do i = 1, len(text)
      if (text(i:i) /= ',') cycle
      token = trim(adjustl(text(start:i - 1)))
      repeats = 1
      star = index(token, '*')
      if (star > 0) then
        read(token(1:star - 1), *, iostat=ios) repeats
        if (ios /= 0) repeats = 1
        token = trim(adjustl(token(star + 1:)))
      end if
      if (len(token) > 0) then
        do r = 1, max(repeats, 1)
          tokens = [character(len=64) :: tokens, token]
        end do
      end if
      start = i + 1
    end do
  end function item_tokens

  !> Every element that reads as a number is finite (logicals and text are not numbers).
  logical function item_is_finite(item)
    type(namelist_item_t), intent(in) :: item
    character(len=64), allocatable :: tokens(:)
    real(wp) :: x
    integer :: k, ios
    item_is_finite = .true.
    if (item_is_text(item)) return
    tokens = item_tokens(item)
    do k = 1, size(tokens)
      read(tokens(k), *, iostat=ios) x
      if (ios == 0) then
        if (.not. ieee_is_finite(x)) item_is_finite = .false.
      end if
    end do
  end function item_is_finite
end module namelist_text
