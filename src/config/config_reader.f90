!> Reading and checking the whole deck, before anything is allocated; command-line overrides
!> (`--set group.variable=value`) are merged into the deck text and checked with it.
module config_reader
  use agglo_kinds, only: wp
  use agglo_config, only: agglo_config_t, deck_group_names
  use config_checks, only: check_cross_groups, check_every_value, check_scene_combinations
  use deck_file, only: deck_t, deck_load, deck_check_groups, deck_group_close, lower
  use error_handling, only: fatal
  use config_run, only: read_run_group, check_run_group
  use config_grid, only: read_grid_group, check_grid_group, smallest_spacing
  use config_fluid, only: read_fluid_group, check_fluid_group
  use config_scene, only: read_scene_group, check_scene_group
  use config_output, only: read_output_group, check_output_group
  use config_forcing, only: read_forcing_group, check_forcing_group
  use config_pair, only: read_pair_group, check_pair_group
  use config_dlvo, only: read_dlvo_group, check_dlvo_group
  use config_collision, only: read_collision_group, check_collision_group, default_lubrication_handover
  use config_bodies, only: read_bodies_group, read_body_file, check_bodies_group
  use config_suspension, only: read_suspension_group, check_suspension_group
  implicit none
  private
  public :: read_config, parse_config, read_groups, apply_override

contains

  !> Load the deck file (rank 0 reads, all ranks receive it), merge the overrides, parse and check.
  !> The file alone is read first, so an error in it names its own line numbers.
  subroutine read_config(path, nranks, cfg, overrides, deck)
    character(len=*), intent(in) :: path
    integer, intent(in) :: nranks
    type(agglo_config_t), intent(out) :: cfg
    character(len=*), intent(in), optional :: overrides(:)
    type(deck_t), intent(out), optional :: deck       !< the deck text with the overrides merged
    type(deck_t) :: text
    integer :: k
    call deck_load(path, text)
    if (present(overrides)) then
      if (size(overrides) > 0) then
        call deck_check_groups(text, deck_group_names)
        call read_groups(text, cfg)
        do k = 1, size(overrides)
          call apply_override(text, trim(overrides(k)))
        end do
      end if
    end if
    call parse_config(text, nranks, cfg)
    cfg%deck_path = path
    if (present(deck)) then
      call move_alloc(text%path, deck%path)
      call move_alloc(text%lines, deck%lines)
    end if
  end subroutine read_config

  !> Every group is read (defaults where absent) and checked; groups that the scene does not
  !> switch on are read too, so a typo in them is still caught, but only checked when used.
  subroutine parse_config(deck, nranks, cfg)
    type(deck_t), intent(in) :: deck
    integer, intent(in) :: nranks
    type(agglo_config_t), intent(out) :: cfg
    real(wp) :: spacing
    call deck_check_groups(deck, deck_group_names)
    call read_groups(deck, cfg)
    ! &collision lubrication_handover = 0 (its default): the gap of the scene's rung (calibrated with
    ! resolved particles, one &pair radius without a resolved squeeze flow). A grid without cells
    ! gets the resolved value here and its own error from check_grid_group.
    if (cfg%collision%lubrication_handover == 0.0_wp) then
      spacing = 0.0_wp
      if (min(cfg%grid%nx, cfg%grid%ny, cfg%grid%nz) > 0) spacing = smallest_spacing(cfg%grid)
      if (.not. (spacing > 0.0_wp)) spacing = huge(1.0_wp)
      cfg%collision%lubrication_handover = default_lubrication_handover(cfg%scene%fluid, cfg%scene%particle_coupling, &
                                                                        cfg%fluid%pressure_scheme, cfg%pair%radius, spacing)
      if (.not. (cfg%collision%lubrication_handover > 0.0_wp)) cfg%collision%lubrication_handover = 0.5_wp
    end if
    call check_every_value(cfg)
    call check_run_group(cfg%run)
    call check_scene_group(cfg%scene)
    call check_scene_combinations(cfg)
    call check_output_group(cfg%output)
    if (cfg%scene%fluid /= 'none') call check_fluid_group(cfg%fluid)
    ! The lubrication hand-over gap is counted in &grid cells in every scene.
    if (cfg%scene%fluid == 'resolved' .or. cfg%collision%lubrication) call check_grid_group(cfg%grid)
    if (cfg%scene%forcing /= 'none') call check_forcing_group(cfg%forcing)
    if (cfg%scene%particles == 'prescribed' .or. cfg%scene%particles == 'free') then
      if (len_trim(cfg%bodies%file) > 0) call read_body_file(cfg%bodies)
      call check_bodies_group(cfg%bodies)
    end if
    ! A suspension lives in the periodic box of &grid, with any fluid.
    if (cfg%scene%particles == 'suspension') then
      call check_grid_group(cfg%grid)
      call check_suspension_group(cfg%suspension)
    end if
    ! Free bodies take their material, integrator and DLVO radius from &pair (docs/decks.md, &bodies).
    if (cfg%scene%particles == 'pair' .or. cfg%scene%particles == 'free' .or. cfg%scene%particles == 'suspension') then
      call check_pair_group(cfg%pair)
      if (cfg%scene%dlvo) call check_dlvo_group(cfg%dlvo)
      if (cfg%scene%collisions .or. cfg%collision%lubrication) call check_collision_group(cfg%collision)
    end if
    call check_cross_groups(cfg, nranks)
  end subroutine parse_config

  !> Every group's namelist read from the deck (defaults where a group or variable is absent).
  subroutine read_groups(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(agglo_config_t), intent(inout) :: cfg
    call read_run_group(deck, cfg%run)
    call read_scene_group(deck, cfg%scene)
    call read_grid_group(deck, cfg%grid)
    call read_fluid_group(deck, cfg%fluid)
    call read_forcing_group(deck, cfg%forcing)
    call read_pair_group(deck, cfg%pair)
    call read_dlvo_group(deck, cfg%dlvo)
    call read_collision_group(deck, cfg%collision)
    call read_output_group(deck, cfg%output)
    call read_bodies_group(deck, cfg%bodies)
    call read_suspension_group(deck, cfg%suspension)
  end subroutine read_groups

  !> Merge one "group.variable=value" into the deck text: the assignment goes on its own line just
  !> before the group's closing "/" (a namelist read keeps the last value a variable is given), or
  !> a new group is appended. The override is first read on its own, as a one-line deck named
  !> after it, so every error (unknown group or variable, wrong type, unclosed quote) names it.
  subroutine apply_override(deck, override)
    type(deck_t), intent(inout) :: deck
    character(len=*), intent(in) :: override
    type(deck_t) :: single
    type(agglo_config_t) :: scratch
    character(len=:), allocatable :: group, variable, value, assignment, lines(:)
    integer :: dot, eq, line_number, column, width, n, k, extra
    eq = index(override, '=')
    dot = index(override(1:max(eq, 1)), '.')
    if (dot < 2 .or. eq < dot + 2) call fatal('--set '''//override//''' is not allowed; allowed: '// &
        'GROUP.VARIABLE=VALUE with VALUE as written in a deck, e.g. --set run.end_time=2e-3 '// &
        'or --set "scene.fluid=''stokes''"')
    group = lower(override(1:dot - 1))
    variable = lower(override(dot + 1:eq - 1))
    value = override(eq + 1:)
    if (verify(group, 'abcdefghijklmnopqrstuvwxyz0123456789_') /= 0 .or. .not. any(deck_group_names == group)) &
        call fatal('--set '''//override//''': unknown namelist group &'//group//'; known groups: '// &
        known_groups())
    if (verify(variable, 'abcdefghijklmnopqrstuvwxyz0123456789_(),: ') /= 0) call fatal('--set '''//override// &
        ''': "'//variable//'" is not a variable name')
    if (len_trim(value) == 0) call fatal('--set '''//override//''': no value after "="')
    assignment = variable//' = '//trim(value)
    single%path = '--set '//override
    allocate(character(len=len(group) + len(assignment) + 4) :: single%lines(1))
    single%lines(1) = '&'//group//' '//assignment//' /'
    call deck_check_groups(single, deck_group_names)
    call deck_group_close(single, group, line_number, column)
    if (column /= len_trim(single%lines(1))) call fatal('--set '''//override//''': the value ends the group '// &
        '(a "/" outside quotes); one variable per --set')
    call read_groups(single, scratch)

    ! The merged text: a copy of the lines, then the deck's lines re-allocated to hold it.
    call deck_group_close(deck, group, line_number, column)
    n = size(deck%lines)
    width = max(len(deck%lines), len(assignment) + 2, len(group) + len(assignment) + 4)
    allocate(character(len=width) :: lines(n))
    do k = 1, n
      lines(k) = deck%lines(k)
    end do
    deallocate(deck%lines)
    if (line_number > 0) then
      ! "...  /" becomes "..." + the assignment + "/"; a "/" alone on its line gets the assignment before it
      extra = merge(1, 2, len_trim(lines(line_number)(1:column - 1)) == 0)
      allocate(character(len=width) :: deck%lines(n + extra))
      do k = 1, line_number - 1
        deck%lines(k) = lines(k)
      end do
      if (extra == 2) deck%lines(line_number) = lines(line_number)(1:column - 1)
      deck%lines(line_number + extra - 1) = '  '//assignment
      deck%lines(line_number + extra) = lines(line_number)(column:)
      do k = line_number + 1, n
        deck%lines(k + extra) = lines(k)
      end do
    else
      allocate(character(len=width) :: deck%lines(n + 1))
      do k = 1, n
        deck%lines(k) = lines(k)
      end do
      deck%lines(n + 1) = '&'//group//' '//assignment//' /'
    end if
  end subroutine apply_override

  function known_groups() result(text)
    character(len=:), allocatable :: text
    integer :: k
    text = ''
    do k = 1, size(deck_group_names)
      text = text//' &'//trim(deck_group_names(k))
    end do
    text = text(2:)
  end function known_groups
end module config_reader
