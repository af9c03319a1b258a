!> The input deck as text: read once on rank 0, broadcast, then every rank parses the same
!> namelist groups from the in-memory copy (identical results on every rank by construction).
!> Also the shared checks that give every deck error the same form:
!> "deck: &group variable = value is not allowed; allowed: range".
module deck_file
  use mpi_f08, only: MPI_Bcast, MPI_INTEGER, MPI_CHARACTER, MPI_COMM_WORLD, MPI_Comm_rank
  use agglo_kinds, only: wp
  use error_handling, only: fatal, input_error
  use text_format, only: real_text, int_text   ! passed on to the config modules
  implicit none
  private
  public :: deck_t, deck_line_length, deck_load, deck_check_groups, &
            check_namelist_read, require_positive, require_nonnegative, require_range, require_option, &
            require_positive_int, real_text, int_text

  integer, parameter :: deck_line_length = 512

  type :: deck_t
    character(len=:), allocatable :: path
    character(len=deck_line_length), allocatable :: lines(:)
  end type deck_t

contains

  !> Read the deck file on rank 0 and broadcast its lines to every rank.
  subroutine deck_load(path, deck)
    character(len=*), intent(in) :: path
    type(deck_t), intent(out) :: deck
    integer :: rank, unit, ios, nlines, i
    logical :: exists
    character(len=deck_line_length) :: line
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    nlines = -1
    if (rank == 0) then
      inquire(file=path, exist=exists)
      if (exists) then
        open(newunit=unit, file=path, status='old', action='read', iostat=ios)
        if (ios == 0) then
          nlines = 0
          do
            read(unit, '(a)', iostat=ios) line
            if (ios /= 0) exit
            nlines = nlines + 1
          end do
          close(unit)
        end if
      end if
    end if
    call MPI_Bcast(nlines, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    if (nlines < 0) call fatal('deck: cannot read the input deck "'//trim(path)//'" (missing or unreadable file)')
    allocate(deck%lines(max(nlines, 1)))
    deck%lines = ''
    if (rank == 0) then
      open(newunit=unit, file=path, status='old', action='read')
      do i = 1, nlines
        read(unit, '(a)') deck%lines(i)
      end do
      close(unit)
    end if
    call MPI_Bcast(deck%lines, len(deck%lines) * size(deck%lines), MPI_CHARACTER, 0, MPI_COMM_WORLD)
    deck%path = path
  end subroutine deck_load

  !> Every "&name" in the deck must be a known group, appear once and be closed by "/".
  !> (A namelist read silently skips groups it was not asked for, so a typo like &grdi would
  !> otherwise be ignored and its values lost without a word.)
  subroutine deck_check_groups(deck, known)
    type(deck_t), intent(in) :: deck
    character(len=*), intent(in) :: known(:)
    character(len=64) :: seen(100), name
    integer :: nseen, i, k
    logical :: inside
    character(len=:), allocatable :: allowed
    allowed = ''
    do k = 1, size(known)
      allowed = allowed//' &'//trim(known(k))
    end do
    nseen = 0
    inside = .false.
    do i = 1, size(deck%lines)
      call scan_line(deck%lines(i), inside, name)
      if (len_trim(name) == 0) cycle
      if (.not. any(known == name)) call fatal('deck: unknown namelist group &'//trim(name)// &
          ' (line '//int_text(i)//' of '//deck%path//'); known groups:'//allowed)
      if (nseen > 0) then
        if (any(seen(1:nseen) == name)) call fatal('deck: namelist group &'//trim(name)// &
            ' appears more than once (line '//int_text(i)//' of '//deck%path//')')
      end if
      nseen = min(nseen + 1, size(seen))
      seen(nseen) = name
    end do
    if (inside) call fatal('deck: the last namelist group in '//deck%path//' is not closed by "/"')
  end subroutine deck_check_groups

  !> Find a group opening "&name" on a line and track whether a group is open.
  subroutine scan_line(line, inside, opened)
    character(len=*), intent(in) :: line
    logical, intent(inout) :: inside
    character(len=*), intent(out) :: opened
    integer :: i, j
    character(len=1) :: quote
    opened = ''
    quote = ' '
    i = 1
    do while (i <= len_trim(line))
      if (quote /= ' ') then
        if (line(i:i) == quote) quote = ' '
      else if (line(i:i) == '''' .or. line(i:i) == '"') then
        quote = line(i:i)
      else if (line(i:i) == '!') then
        exit
      else if (line(i:i) == '&' .and. .not. inside) then
        j = i + 1
        do while (j <= len_trim(line))
          if (scan(line(j:j), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') == 0) exit
          j = j + 1
        end do
        opened = lower(line(i + 1:j - 1))
        inside = .true.
        i = j - 1
      else if (line(i:i) == '/' .and. inside) then
        inside = .false.
      end if
      i = i + 1
    end do
  end subroutine scan_line

  pure function lower(text) result(out)
    character(len=*), intent(in) :: text
    character(len=len(text)) :: out
    integer :: i
    out = text
    do i = 1, len(text)
      if (text(i:i) >= 'A' .and. text(i:i) <= 'Z') out(i:i) = achar(iachar(text(i:i)) + 32)
    end do
  end function lower

  !> Turn a failed namelist read into a deck error naming the group and where it stands.
  subroutine check_namelist_read(deck, group, ios, message)
    type(deck_t), intent(in) :: deck
    character(len=*), intent(in) :: group, message
    integer, intent(in) :: ios
    if (ios > 0) call fatal('deck: cannot read namelist group &'//trim(group)//' ('//group_lines(deck, group)// &
        ' of '//deck%path//'): '//trim(message)// &
        ' (an unknown variable name, a value of the wrong type, or a missing quote; see docs/decks.md)')
  end subroutine check_namelist_read

  !> "lines 3-7": where group opens and closes in the deck.
  function group_lines(deck, group) result(text)
    type(deck_t), intent(in) :: deck
    character(len=*), intent(in) :: group
    character(len=:), allocatable :: text
    character(len=64) :: name
    integer :: i, first, last
    logical :: inside, in_group
    first = 0
    last = 0
    inside = .false.
    in_group = .false.
    do i = 1, size(deck%lines)
      call scan_line(deck%lines(i), inside, name)
      if (name == lower(group)) then
        first = i
        in_group = .true.
      end if
      if (in_group) last = i
      if (in_group .and. .not. inside) exit
    end do
    if (first == last) then
      text = 'line '//int_text(first)
    else
      text = 'lines '//int_text(first)//'-'//int_text(last)
    end if
  end function group_lines

  subroutine require_positive(group, variable, value)
    character(len=*), intent(in) :: group, variable
    real(wp), intent(in) :: value
    if (.not. (value > 0.0_wp)) call input_error(group, variable, real_text(value), '> 0')
  end subroutine require_positive

  subroutine require_nonnegative(group, variable, value)
    character(len=*), intent(in) :: group, variable
    real(wp), intent(in) :: value
    if (.not. (value >= 0.0_wp)) call input_error(group, variable, real_text(value), '>= 0')
  end subroutine require_nonnegative

  !> lower <= value <= upper (NaN fails).
  subroutine require_range(group, variable, value, lower_bound, upper_bound)
    character(len=*), intent(in) :: group, variable
    real(wp), intent(in) :: value, lower_bound, upper_bound
    if (.not. (value >= lower_bound .and. value <= upper_bound)) call input_error(group, variable, &
        real_text(value), '['//real_text(lower_bound)//', '//real_text(upper_bound)//']')
  end subroutine require_range

  subroutine require_positive_int(group, variable, value)
    character(len=*), intent(in) :: group, variable
    integer, intent(in) :: value
    if (value <= 0) call input_error(group, variable, int_text(value), 'an integer >= 1')
  end subroutine require_positive_int

  !> value must be one of options (case-sensitive, as documented).
  subroutine require_option(group, variable, value, options)
    character(len=*), intent(in) :: group, variable, value
    character(len=*), intent(in) :: options(:)
    character(len=:), allocatable :: allowed
    integer :: k
    if (any(options == value)) return
    allowed = ''
    do k = 1, size(options)
      allowed = allowed//merge(' | ', '   ', k > 1)//''''//trim(options(k))//''''
    end do
    call input_error(group, variable, ''''//trim(value)//'''', 'one of '//allowed(4:))
  end subroutine require_option
end module deck_file
