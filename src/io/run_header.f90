!> The head of every run log: what was built how, on what, with which deck.
!> The deck echo is run.nml with the namelist padding removed (character variables are written
!> padded to their full length); the compiler options are summarised and wrapped.
module run_header
  use, intrinsic :: iso_fortran_env, only: compiler_version, compiler_options
  use mpi_f08, only: MPI_Get_library_version, MPI_MAX_LIBRARY_VERSION_STRING
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  use parallel_env, only: n_ranks, is_root
  use run_directory, only: run_directory_path, run_file
  use text_format, only: int_text
  use file_system, only: read_whole_line
  implicit none
  private
  public :: log_run_header, compact_namelist_line, compiler_options_summary, wrap_words

  !> Width of a wrapped header line (the label column included).
  integer, parameter :: header_width = 100
  character(len=*), parameter :: label_indent = '            '

contains

  subroutine log_run_header(cfg)
    type(agglo_config_t), intent(in) :: cfg
    character(len=MPI_MAX_LIBRARY_VERSION_STRING) :: mpi_version
    character(len=32) :: ranks_text
    character(len=:), allocatable :: line, lines(:)
    integer :: length, unit, ios, i
    call MPI_Get_library_version(mpi_version, length)
    write(ranks_text, '(i0)') n_ranks
    call log_line('Agglo: particle-resolved DNS of attractive spheroid pairs')
    call log_line('  compiler: '//compiler_version())
    lines = wrap_words(compiler_options_summary(compiler_options()), header_width - len(label_indent))
    do i = 1, size(lines)
      call log_line(merge('  options:  ', label_indent, i == 1)//trim(lines(i)))
    end do
    call log_line('  MPI:      '//trim(first_line(mpi_version(1:length))))
    call log_line('  ranks:    '//trim(ranks_text))
    call log_line('  deck:     '//trim(cfg%deck_path))
    call log_line('  output:   '//run_directory_path())
    call log_line('  run:      '//trim(cfg%run%name)//trim(merge(' (restart)', '          ', cfg%run%restart)))
    call log_line('Resolved deck (run.nml):')
    if (is_root()) then
      open(newunit=unit, file=run_file('run.nml'), status='old', action='read', iostat=ios)
      do while (ios == 0)
        call read_whole_line(unit, line, ios)
        if (ios == 0) call log_line('  '//compact_namelist_line(line))
      end do
      close(unit)
    end if
  end subroutine log_run_header

  !> One namelist output line without its padding: trailing blanks inside a quoted value
  !> (NAME="run      ", -> NAME="run",), blanks before a comma and after '=' (X=  7.5   , -> X=7.5,),
  !> runs of blanks between items (one kept) and at the end. Blanks inside a value other than its
  !> trailing padding stay, and so do quotes doubled inside a value ("" or '').
  pure function compact_namelist_line(line) result(compact)
    character(len=*), intent(in) :: line
    character(len=:), allocatable :: compact
    character(len=len(line)) :: buffer
    character :: quote
    integer :: i, n, blanks, first
    first = verify(line, ' ')
    if (first > 0) then
      if (line(first:first) == '!') then              ! a comment line is copied as it is
        compact = trim(line)
        return
      end if
    end if
    n = 0
    quote = ' '
    blanks = 0   ! blanks read but not yet copied (inside a value) or dropped (before a comma)
    i = 1
    do while (i <= len(line))
      if (quote /= ' ') then
        if (line(i:i) == quote .and. i < len(line)) then
          if (line(i + 1:i + 1) == quote) then        ! a doubled quote: one character of the value
            call emit_blanks(buffer, n, blanks)
            buffer(n + 1:n + 2) = line(i:i + 1)
            n = n + 2
            i = i + 2
            cycle
          end if
        end if
        if (line(i:i) == quote) then                  ! closing quote: the pending blanks were padding
          blanks = 0
          quote = ' '
          n = n + 1
          buffer(n:n) = line(i:i)
        else if (line(i:i) == ' ') then
          blanks = blanks + 1
        else
          call emit_blanks(buffer, n, blanks)
          n = n + 1
          buffer(n:n) = line(i:i)
        end if
      else if (line(i:i) == ' ') then
        blanks = blanks + 1
      else
        ! Outside values one blank separates items; none before a comma or after '=', and the
        ! line's indentation stays.
        if (n > 0) blanks = min(blanks, 1)
        if (line(i:i) == ',') blanks = 0
        if (n > 0) then
          if (buffer(n:n) == '=') blanks = 0
        end if
        call emit_blanks(buffer, n, blanks)
        n = n + 1
        buffer(n:n) = line(i:i)
        if (line(i:i) == '"' .or. line(i:i) == "'") quote = line(i:i)
      end if
      i = i + 1
    end do
    if (quote /= ' ') call emit_blanks(buffer, n, blanks)              ! an unclosed value keeps its text
    compact = buffer(1:n)

  contains

    pure subroutine emit_blanks(buffer, n, blanks)
      character(len=*), intent(inout) :: buffer
      integer, intent(inout) :: n, blanks
      buffer(n + 1:n + blanks) = ' '
      n = n + blanks
      blanks = 0
    end subroutine emit_blanks
  end function compact_namelist_line

  !> The compiler options without include and module paths (-I, -J, -fpre-include) and with the
  !> instruction-set and cache switches that -march=native expands into (-mavx2, -mno-xop,
  !> --param=l1-cache-size=32, ...) counted, the enabled vector extensions named: what decides the
  !> arithmetic, in a line or two.
  pure function compiler_options_summary(options) result(summary)
    character(len=*), intent(in) :: options
    character(len=:), allocatable :: summary
    character(len=*), parameter :: vector_sets(6) = [character(len=8) :: 'sse4.2', 'avx', 'avx2', 'fma', 'avx512f', &
                                                      'avx512vl']
    character(len=:), allocatable :: token, vectors
    integer :: first, last, isa_flags, k
    logical :: skip_next
    summary = ''
    vectors = ''
    isa_flags = 0
    skip_next = .false.
    last = 0
    do
      call next_token(options, last, first)
      if (first == 0) exit
      token = options(first:last)
      if (skip_next) then
        skip_next = .false.
      else if (token == '-I' .or. token == '-J') then
        skip_next = .true.                            ! the path follows as a separate word
      else if (starts_with(token, '-I') .or. starts_with(token, '-J') .or. starts_with(token, '-fpre-include=')) then
        continue
      else if (starts_with(token, '--param=') .or. starts_with(token, '-m') .and. .not. (starts_with(token, '-march=') .or. &
               starts_with(token, '-mtune=') .or. starts_with(token, '-mprefer-vector-width='))) then
        isa_flags = isa_flags + 1
        do k = 1, size(vector_sets)
          if (token == '-m'//trim(vector_sets(k))) vectors = vectors//' '//trim(vector_sets(k))
        end do
      else
        summary = summary//' '//token
      end if
    end do
    if (isa_flags > 0) then
      summary = summary//' ('//int_text(isa_flags)//' instruction-set and cache switches'
      if (len(vectors) > 0) summary = summary//'; vectors:'//vectors
      summary = summary//')'
    end if
    summary = adjustl(summary)
    summary = trim(summary)
  end function compiler_options_summary

  !> text cut at blanks into lines of at most width characters (a longer word gets its own line).
  pure function wrap_words(text, width) result(lines)
    character(len=*), intent(in) :: text
    integer, intent(in) :: width
    character(len=:), allocatable :: lines(:)
    character(len=:), allocatable :: pieces(:)
    integer :: first, last, n, words, longest, line_length
    words = 0
    longest = 1
    last = 0
    do
      call next_token(text, last, first)
      if (first == 0) exit
      words = words + 1
      longest = max(longest, last - first + 1)
    end do
    allocate(character(len=max(width, longest)) :: pieces(max(1, words)))
    n = 1
    pieces(1) = ''
    line_length = 0
    last = 0
    do
      call next_token(text, last, first)
      if (first == 0) exit
      if (line_length > 0 .and. line_length + 1 + (last - first + 1) > width) then
        n = n + 1
        pieces(n) = ''
        line_length = 0
      end if
      if (line_length == 0) then
        pieces(n) = text(first:last)
        line_length = last - first + 1
      else
        pieces(n)(line_length + 1:) = ' '//text(first:last)
        line_length = line_length + 1 + (last - first + 1)
      end if
    end do
    lines = pieces(1:n)
  end function wrap_words

  !> The next blank-separated word of text after position last: text(first:last), first = 0 at the end.
  pure subroutine next_token(text, last, first)
    character(len=*), intent(in) :: text
    integer, intent(inout) :: last
    integer, intent(out) :: first
    integer :: i
    first = 0
    i = last + 1
    do while (i <= len(text))
      if (text(i:i) /= ' ') exit
      i = i + 1
    end do
    if (i > len(text)) return
    first = i
    do while (i <= len(text))
      if (text(i:i) == ' ') exit
      i = i + 1
    end do
    last = i - 1
  end subroutine next_token

  pure logical function starts_with(text, prefix)
    character(len=*), intent(in) :: text, prefix
    starts_with = len(text) >= len(prefix)
    if (starts_with) starts_with = text(1:len(prefix)) == prefix
  end function starts_with

  function first_line(text) result(line)
    character(len=*), intent(in) :: text
    character(len=len(text)) :: line
    integer :: cut
    cut = index(text, new_line('a'))
    line = text
    if (cut > 0) line = text(1:cut - 1)
  end function first_line
end module run_header
