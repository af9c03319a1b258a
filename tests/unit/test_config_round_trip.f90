! checks: 34
!> Configuration round trip: every deck variable set to a value other than its default, read as a
!> deck, written back (the resolved deck run.nml is this namelist output), compared variable by
!> variable. A variable lives in five places of its config_<group> module (type component, namelist
!> object, namelist group, to_namelist, from_namelist); one left out of from_namelist keeps its
!> default, one left out of to_namelist keeps a stale value from the previous read (caught by
!> reading an empty deck after the mutated one), a group left out of write_config or read_groups
!> is missing or keeps its defaults. The variables come from the namelist output itself, so a new
!> variable is covered without editing this test.
program test_config_round_trip
  use agglo_kinds, only: wp
  use agglo_config, only: agglo_config_t, config_items, deck_group_names
  use config_reader, only: read_groups
  use deck_file, only: deck_t
  use namelist_text, only: namelist_item_t, item_is_text, item_text_values, item_tokens
  use text_format, only: int_text
  use test_framework, only: test_start, test_finish, check
  implicit none
  type(agglo_config_t) :: defaults, mutated, after
  type(namelist_item_t), allocatable :: default_items(:), written(:), again(:)
  character(len=:), allocatable :: mutated_values(:)
  type(deck_t) :: deck, empty
  character(len=:), allocatable :: wrong
  integer :: k, g, n
  logical :: found
  integer, parameter :: longest_value = 8000   !< room for a mutated array of about 300 reals

  call test_start('config_round_trip')
  default_items = config_items(defaults)
  n = size(default_items)
  call check(n >= 60, 'every_variable_is_written', 'variables: '//int_text(n))
  do g = 1, size(deck_group_names)
    found = .false.
    do k = 1, n
      if (default_items(k)%group == trim(deck_group_names(g))) found = .true.
    end do
    call check(found, 'group_written_'//trim(deck_group_names(g)))
  end do

  ! The mutated deck: one "name = value" line per variable, grouped as written.
  allocate(character(len=longest_value) :: mutated_values(n))
  allocate(character(len=longest_value + 100) :: deck%lines(n + 2 * size(deck_group_names)))
  deck%lines = ''
  deck%path = 'round-trip deck'
  g = 0
  do k = 1, n
    mutated_values(k) = mutate(default_items(k))
    if (k == 1) then
      g = g + 1; deck%lines(g) = '&'//default_items(k)%group
    else if (default_items(k)%group /= default_items(k - 1)%group) then
      g = g + 1; deck%lines(g) = '/'
      g = g + 1; deck%lines(g) = '&'//default_items(k)%group
    end if
    g = g + 1; deck%lines(g) = '  '//default_items(k)%name//' = '//trim(mutated_values(k))
  end do
  g = g + 1; deck%lines(g) = '/'
  call read_groups(deck, mutated)
  written = config_items(mutated)

  do g = 1, size(deck_group_names)
    wrong = ''
    do k = 1, min(n, size(written))
      if (written(k)%group /= trim(deck_group_names(g))) cycle
      if (written(k)%name /= default_items(k)%name .or. .not. same_value(written(k), trim(mutated_values(k)))) &
          wrong = wrong//' '//written(k)%name//' (set '//trim(mutated_values(k))//', read back '//written(k)%value//')'
    end do
    call check(size(written) == n .and. len(wrong) == 0, 'set_and_read_back_'//trim(deck_group_names(g)), wrong)
  end do

  ! A deck without any value after the mutated one: every variable is back at its default.
  allocate(character(len=1) :: empty%lines(1))
  empty%lines = ''
  empty%path = 'empty deck'
  call read_groups(empty, after)
  again = config_items(after)
  do g = 1, size(deck_group_names)
    wrong = ''
    do k = 1, min(n, size(again))
      if (again(k)%group /= trim(deck_group_names(g))) cycle
      if (again(k)%value /= default_items(k)%value) wrong = wrong//' '//again(k)%name//' = '//again(k)%value
    end do
    call check(size(again) == n .and. len(wrong) == 0, 'defaults_after_another_deck_'//trim(deck_group_names(g)), wrong)
  end do
  call test_finish()

contains

  !> A value of the same type that differs from the default: text 'zq' in every element, the other
  !> logical, an integer plus one, a real 0.5 x + 0.375 k for element k (never x itself).
  function mutate(item) result(text)
    type(namelist_item_t), intent(in) :: item
    character(len=longest_value) :: text
    character(len=64), allocatable :: tokens(:)
    character(len=32) :: number
    real(wp) :: x, y
    integer :: i, j, ios
    if (item_is_text(item)) then
      text = '''zq'''
      do j = 2, size(item_text_values(item))
        text = trim(text)//', ''zq'''
      end do
      return
    end if
    tokens = item_tokens(item)
    text = ''
    do j = 1, size(tokens)
      if (tokens(j) == 'T' .or. tokens(j) == 'F') then
        number = merge('.false.', '.true. ', tokens(j) == 'T')
      else if (scan(tokens(j), '.EeNn') == 0) then
        read(tokens(j), *) i
        write(number, '(i0)') i + 1
      else
        read(tokens(j), *, iostat=ios) x
        y = 0.5_wp * x + 0.375_wp * j
        if (y == x) y = x + 1.0_wp
        write(number, '(es25.17)') y
      end if
      text = trim(text)//merge(', ', '  ', j > 1)//adjustl(number)
    end do
    text = adjustl(text)
  end function mutate

  !> The value written equals the value set: text without its padding, logicals, and numbers read
  !> from both texts (a value stored and read back, so exact equality is the test).
  logical function same_value(item, set_text)
    type(namelist_item_t), intent(in) :: item
    character(len=*), intent(in) :: set_text
    character(len=64), allocatable :: got(:), want(:)
    type(namelist_item_t) :: set_item
    real(wp) :: a, b
    integer :: j, ios_a, ios_b
    set_item%group = item%group
    set_item%name = item%name
    set_item%value = set_text
    if (item_is_text(item)) then
      same_value = size(item_text_values(item)) == size(item_text_values(set_item))
      if (same_value) same_value = all(item_text_values(item) == item_text_values(set_item))
      return
    end if
    got = item_tokens(item)
    want = item_tokens(set_item)
    same_value = (size(got) == size(want))
    if (.not. same_value) return
    do j = 1, size(got)
      if (got(j) == 'T' .or. got(j) == 'F') then
        same_value = same_value .and. ((got(j) == 'T') .eqv. (want(j) == '.true.'))
      else
        read(got(j), *, iostat=ios_a) a
        read(want(j), *, iostat=ios_b) b
        same_value = same_value .and. ios_a == 0 .and. ios_b == 0 .and. a == b
      end if
    end do
  end function same_value
end program test_config_round_trip
