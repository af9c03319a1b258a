!> The input deck as text: read once on rank 0, broadcast, then every rank parses the same
!> namelist groups from the in-memory copy (identical results on every rank by construction).
!> Also the shared checks that give every deck error the same form:
!> "deck: &group variable = value is not allowed; allowed: range".
module deck_file
  use file_system, only: read_whole_line
  use mpi_f08, only: MPI_Bcast, MPI_INTEGER, MPI_CHARACTER, MPI_COMM_WORLD, MPI_Comm_rank
  use agglo_kinds, only: wp
  use error_handling, only: fatal, input_error
  use text_format, only: real_text, int_text   ! passed on to the config modules
  implicit none
  private
  public :: deck_t, deck_load, text_file_load, deck_check_groups, deck_group_close, lower, &
            check_namelist_read, require_positive, require_nonnegative, require_range, require_option, &
            require_positive_int, real_text, int_text

  !> The deck's lines, as long as the longest line of the file (any length is read whole).
  type :: deck_t
    character(len=:), allocatable :: path
    character(len=:), allocatable :: lines(:)
  end type deck_t

  character(len=*), parameter :: name_characters = &
      'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_'

contains

  !> Read the deck file on rank 0 and broadcast its lines to every rank.
  subroutine deck_load(path, deck)
    character(len=*), intent(in) :: path
    type(deck_t), intent(out) :: deck
    logical :: readable
    call text_file_load(path, deck%lines, readable)
    if (.not. readable) call fatal('deck: cannot read the input deck "'//trim(path)//'" (missing or unreadable file)')
    deck%path = path
  end subroutine deck_load

  !> The lines of a text file the deck names, read on rank 0 and broadcast to every rank
  !> (collective; readable is the same on every rank, and lines one blank line when it is false).
  subroutine text_file_load(path, lines, readable)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: lines(:)
    logical, intent(out) :: readable
    integer :: rank, unit, ios, counts(2), i
    logical :: exists
    character(len=:), allocatable :: line
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    counts = -1            ! number of lines, longest line
    if (rank == 0) then
      inquire(file=path, exist=exists)
      if (exists) then
        open(newunit=unit, file=path, status='old', action='read', iostat=ios)
        if (ios == 0) then
          counts = 0
          do
            call read_whole_line(unit, line, ios)
            if (ios /= 0) exit
            counts = [counts(1) + 1, max(counts(2), len(line))]
          end do
          close(unit)
        end if
      end if
    end if
    call MPI_Bcast(counts, 2, MPI_INTEGER, 0, MPI_COMM_WORLD)
    readable = counts(1) >= 0
    allocate(character(len=max(counts(2), 1)) :: lines(max(counts(1), 1)))
    lines = ''
    if (.not. readable) return
    if (rank == 0) then
      open(newunit=unit, file=path, status='old', action='read')
      do i = 1, counts(1)
        call read_whole_line(unit, line, ios)
        lines(i) = line
      end do
      close(unit)
    end if
    call MPI_Bcast(lines, len(lines) * size(lines), MPI_CHARACTER, 0, MPI_COMM_WORLD)
  end subroutine text_file_load

  !> The deck's syntax, beyond what a namelist read checks (a namelist read skips whatever it was
  !> not asked for, so each of these would otherwise drop values without a word):
  !>  - every "&name" is a known group, appears once and is closed by "/" before the next opens;
  !>  - no text outside the groups except "!" comments (a stray "nx = 8" after a "/" is lost);
  !>  - every string closes on the line it opens (an open quote swallows the rest of the group);
  !>  - every "name =" has a value (an empty one, a namelist null value, keeps the default);
  !>  - no "$name ... $end" groups (another dialect, outside these checks);
  !>  - at least one group (an empty file, plain text or JSON is not a deck).
  subroutine deck_check_groups(deck, known)
    type(deck_t), intent(in) :: deck
    character(len=*), intent(in) :: known(:)
    character(len=64) :: seen(100), name
    integer :: nseen, i, k, col, open_line, pending(2)
    logical :: inside
    character(len=1) :: c, quote, previous
    character(len=:), allocatable :: allowed
    allowed = ''
    do k = 1, size(known)
      allowed = allowed//' &'//trim(known(k))
    end do
    nseen = 0
    inside = .false.
    open_line = 0
    k = 0
    pending = 0
    previous = ' '
    do i = 1, size(deck%lines)
      quote = ' '
      col = 1
      do while (col <= len_trim(deck%lines(i)))
        c = deck%lines(i)(col:col)
        if ((iachar(c) < 32 .or. iachar(c) == 127) .and. .not. is_blank(c)) call fatal('deck: '// &
            line_of(deck, i)//': a control character (code '//int_text(iachar(c))//') in column '// &
            int_text(col)//'; a deck is plain text')
        if (quote == ' ' .and. inside .and. c /= '!' .and. .not. is_blank(c)) &
            call track_values(deck, i, col, pending, previous)
        if (quote /= ' ') then
          if (c == quote) quote = ' '
        else if (c == '!') then
          exit
        else if (c == '''' .or. c == '"') then
          if (.not. inside) call outside_text(deck, i, col)
          quote = c
          k = col
        else if (c == '$') then
          call fatal('deck: '//line_of(deck, i)//': "$" groups ($name ... $end) are not supported; '// &
              'write each group as &name ... / (docs/decks.md)')
        else if (c == '&') then
          name = lower(group_name_at(deck%lines(i), col))
          if (inside) call fatal('deck: '//line_of(deck, i)//': "&'//trim(name)//'" inside namelist group &'// &
              trim(seen(nseen))//' (opened on line '//int_text(open_line)//'), which is not closed by "/" '// &
              'before it; close every group with "/"')
          if (len_trim(name) == 0) call fatal('deck: '//line_of(deck, i)//': "&" without a group name; '// &
              'known groups:'//allowed)
          if (.not. any(known == name)) call fatal('deck: unknown namelist group &'//trim(name)// &
              ' ('//line_of(deck, i)//'); known groups:'//allowed)
          if (nseen > 0) then
            if (any(seen(1:nseen) == name)) call fatal('deck: namelist group &'//trim(name)// &
                ' appears more than once ('//line_of(deck, i)//')')
          end if
          nseen = min(nseen + 1, size(seen))
          seen(nseen) = name
          inside = .true.
          open_line = i
          previous = ' '
          col = col + len_trim(name)
        else if (c == '/') then
          if (.not. inside) call outside_text(deck, i, col)
          inside = .false.
        else if (.not. inside .and. .not. is_blank(c)) then
          call outside_text(deck, i, col)
        end if
        col = col + 1
      end do
      if (quote /= ' ') call fatal('deck: '//line_of(deck, i)//': the string opened by '//quote//' in column '// &
          int_text(k)//' is not closed on its line (a missing quote? strings must close on the line '// &
          'they open)')
    end do
    if (inside) call fatal('deck: the last namelist group in '//deck%path//', &'//trim(seen(nseen))// &
        ' (line '//int_text(open_line)//'), is not closed by "/"')
    if (nseen == 0) call fatal('deck: '//deck%path//' holds no namelist group (&name ... /): not an '// &
        'Agglo deck; see docs/decks.md and input/*.nml')
  end subroutine deck_check_groups

  !> Called for each significant character inside a group (outside strings and comments): an "="
  !> must be followed by a value, not by ",", "/", "&" or the next "name =" (a namelist null value
  !> leaves the variable as it was, the default, without a word), and a list has no ",,".
  subroutine track_values(deck, line_number, column, pending, previous)
    type(deck_t), intent(in) :: deck
    integer, intent(in) :: line_number, column
    integer, intent(inout) :: pending(2)          !< line and column of an "=" waiting for its value
    character(len=1), intent(inout) :: previous   !< the previous significant character in the group
    character(len=1) :: c
    c = deck%lines(line_number)(column:column)
    if (pending(1) > 0) then
      if (c == ',' .or. c == '/' .or. c == '&' .or. c == '=' .or. starts_assignment(deck%lines(line_number), column)) &
          call fatal('deck: '//line_of(deck, pending(1))//': "'//trim(name_before(deck%lines(pending(1)), pending(2)))// &
          ' =" has no value (an empty value would keep the default without a word; give a value or '// &
          'leave the variable out)')
      pending = 0
    end if
    if (c == ',' .and. previous == ',') call fatal('deck: '//line_of(deck, line_number)//': an empty value ",," in '// &
        'a list (it would keep that element''s default without a word)')
    if (c == '=') pending = [line_number, column]
    previous = c
  end subroutine track_values

  !> The text at column starts "name =" or "name(" (the next assignment, not a value).
  pure logical function starts_assignment(line, column)
    character(len=*), intent(in) :: line
    integer, intent(in) :: column
    integer :: j
    starts_assignment = .false.
    if (scan(line(column:column), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ') == 0) return
    j = column
    do while (j <= len_trim(line))
      if (scan(line(j:j), name_characters) == 0) exit
      j = j + 1
    end do
    do while (j <= len_trim(line))
      if (.not. is_blank(line(j:j))) exit
      j = j + 1
    end do
    if (j <= len_trim(line)) starts_assignment = (line(j:j) == '=' .or. line(j:j) == '(')
  end function starts_assignment

  !> The variable name (with its subscript) before the "=" at column.
  pure function name_before(line, column) result(name)
    character(len=*), intent(in) :: line
    integer, intent(in) :: column
    character(len=:), allocatable :: name
    integer :: first, last
    last = column - 1
    do while (last > 0)
      if (.not. is_blank(line(last:last))) exit
      last = last - 1
    end do
    first = last
    do while (first > 1)
      if (scan(line(first - 1:first - 1), name_characters//'()') == 0) exit
      first = first - 1
    end do
    name = trim(adjustl(line(max(first, 1):max(last, 0))))
  end function name_before

  !> "line 7 of deck.nml"
  function line_of(deck, line_number) result(text)
    type(deck_t), intent(in) :: deck
    integer, intent(in) :: line_number
    character(len=:), allocatable :: text
    text = 'line '//int_text(line_number)//' of '//deck%path
  end function line_of

  subroutine outside_text(deck, line_number, column)
    type(deck_t), intent(in) :: deck
    integer, intent(in) :: line_number, column
    call fatal('deck: '//line_of(deck, line_number)//': text outside a namelist group: "'// &
        printable(deck%lines(line_number)(column:min(column + 39, len_trim(deck%lines(line_number)))))// &
        '" (values go inside &group ... /; comments start with "!")')
  end subroutine outside_text

  !> The text with every character outside printable ASCII shown as "?" (for messages).
  pure function printable(text) result(out)
    character(len=*), intent(in) :: text
    character(len=len(text)) :: out
    integer :: i
    out = text
    do i = 1, len(text)
      if (iachar(text(i:i)) < 32 .or. iachar(text(i:i)) > 126) out(i:i) = '?'
    end do
  end function printable

  pure logical function is_blank(c)
    character(len=1), intent(in) :: c
    is_blank = (c == ' ' .or. c == achar(9) .or. c == achar(13))
  end function is_blank

  !> The group name after the "&" at column col (letters, digits, underscores).
  pure function group_name_at(line, col) result(name)
    character(len=*), intent(in) :: line
    integer, intent(in) :: col
    character(len=64) :: name
    integer :: j
    j = col + 1
    do while (j <= len_trim(line))
      if (scan(line(j:j), name_characters) == 0) exit
      j = j + 1
    end do
    name = line(col + 1:min(j - 1, col + 64))
  end function group_name_at

  !> Find a group opening "&name" on a line and track whether a group is open (for decks that
  !> passed deck_check_groups: strings close on their line).
  subroutine scan_line(line, inside, opened)
    character(len=*), intent(in) :: line
    logical, intent(inout) :: inside
    character(len=*), intent(out) :: opened
    integer :: i
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
        opened = lower(group_name_at(line, i))
        inside = .true.
        i = i + len_trim(opened)
      else if (line(i:i) == '/' .and. inside) then
        inside = .false.
      end if
      i = i + 1
    end do
  end subroutine scan_line

  !> Where group closes: line and column of its "/" (0, 0 if the deck has no such group).
  !> For decks that passed deck_check_groups.
  subroutine deck_group_close(deck, group, line_number, column)
    type(deck_t), intent(in) :: deck
    character(len=*), intent(in) :: group
    integer, intent(out) :: line_number, column
    character(len=64) :: current
    character(len=1) :: c, quote
    integer :: i, col
    line_number = 0
    column = 0
    current = ''
    do i = 1, size(deck%lines)
      quote = ' '
      col = 1
      do while (col <= len_trim(deck%lines(i)))
        c = deck%lines(i)(col:col)
        if (quote /= ' ') then
          if (c == quote) quote = ' '
        else if (c == '!') then
          exit
        else if (c == '''' .or. c == '"') then
          quote = c
        else if (c == '&' .and. current == '') then
          current = lower(group_name_at(deck%lines(i), col))
          col = col + len_trim(current)
        else if (c == '/' .and. current /= '') then
          if (current == lower(group)) then
            line_number = i
            column = col
            return
          end if
          current = ''
        end if
        col = col + 1
      end do
    end do
  end subroutine deck_group_close

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
