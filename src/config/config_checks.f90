!> Checks that involve more than one namelist group (each group checks itself first).
!> One subroutine per part of the code (fluid, forcing, particles), so each part keeps its rules together.
module config_checks
  use agglo_kinds, only: wp
  use agglo_config, only: agglo_config_t, config_items
  use namelist_text, only: namelist_item_t, item_is_text, item_text_fills, item_text_values, item_is_finite
  use deck_file, only: int_text, real_text
  use config_forcing, only: forcing_mode_extent
  use config_grid, only: smallest_spacing
  use config_suspension, only: species_count, species_semi_axes
  use config_shapes, only: deck_semi_axes
  use error_handling, only: input_error, fatal
  implicit none
  private
  public :: check_cross_groups, check_every_value, check_scene_combinations

contains

  subroutine check_cross_groups(cfg, nranks)
    type(agglo_config_t), intent(in) :: cfg
    integer, intent(in) :: nranks
    if (cfg%scene%fluid == 'resolved') call check_fluid_cross(cfg, nranks)
    if (cfg%scene%forcing /= 'none') call check_forcing_cross(cfg)
    if (cfg%scene%particles == 'pair') call check_particle_cross(cfg)
    if (cfg%scene%particles == 'suspension') call check_suspension_cross(cfg)
    if (cfg%scene%particles == 'pair' .and. cfg%scene%fluid == 'resolved') call check_pair_in_box(cfg)
    if ((cfg%scene%particles == 'prescribed' .or. cfg%scene%particles == 'free') .and. cfg%scene%fluid == 'resolved') &
      call check_bodies_in_box(cfg)
    if (immersed_bodies(cfg)) call check_bodies_thick_enough(cfg)
  end subroutine check_cross_groups

  !> The scene imposes its bodies with the immersed boundary: bodies in prescribed motion, or free
  !> bodies (pair, &bodies, suspension) with &scene particle_coupling = 'resolved'.
  logical function immersed_bodies(cfg)
    type(agglo_config_t), intent(in) :: cfg
    immersed_bodies = cfg%scene%fluid == 'resolved' .and. (cfg%scene%particles == 'prescribed' .or. &
                      (free_particles(cfg) .and. cfg%scene%particle_coupling == 'resolved'))
  end function immersed_bodies

  !> Every body the immersed boundary imposes at least 4 cells of the largest grid spacing thick
  !> (2 min(a, b)): thinner, the ghost layers of its opposite faces overlap (docs/theory.md, "Thin
  !> bodies"). The error names the grid the body needs.
  subroutine check_bodies_thick_enough(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: n
    select case (cfg%scene%particles)
    case ('pair')
      call require_thick_enough('pair', 'radius', cfg%pair%radius, cfg%pair%shape, &
                                deck_semi_axes(cfg%pair%shape, cfg%pair%radius, cfg%pair%aspect_ratio), cfg)
    case ('suspension')
      do n = 1, species_count(cfg%suspension)
        call require_thick_enough('suspension', 'radius('//int_text(n)//')', cfg%suspension%radius(n), &
                                  cfg%suspension%shape(n), species_semi_axes(cfg%suspension, n), cfg)
      end do
    case ('prescribed', 'free')
      do n = 1, cfg%bodies%count
        call require_thick_enough('bodies', 'radius('//int_text(n)//')', cfg%bodies%radius(n), cfg%bodies%shape(n), &
                                  deck_semi_axes(cfg%bodies%shape(n), cfg%bodies%radius(n), cfg%bodies%aspect_ratio(n)), cfg)
      end do
    end select
  end subroutine check_bodies_thick_enough

  !> One body (semi-axes [a, b], m) against the largest grid spacing of &grid; the error names the
  !> deck variable that gave it and the smallest cubic grid that holds it.
  subroutine require_thick_enough(group, variable, radius, shape, semi_axes, cfg)
    character(len=*), intent(in) :: group, variable, shape
    real(wp), intent(in) :: radius, semi_axes(2)
    type(agglo_config_t), intent(in) :: cfg
    real(wp), parameter :: thinnest_cells = 4.0_wp
    real(wp) :: spacing, cells
    character(len=8) :: cells_text
    character(len=:), allocatable :: remedy
    spacing = max(cfg%grid%length_x / cfg%grid%nx, cfg%grid%length_y / cfg%grid%ny, cfg%grid%length_z / cfg%grid%nz)
    cells = 2.0_wp * minval(semi_axes) / spacing
    if (cells >= thinnest_cells) return
    write(cells_text, '(f8.2)') cells
    remedy = ' for this box, or a larger radius'
    if (trim(shape) /= 'sphere') remedy = remedy//' or an aspect_ratio nearer 1'
    call input_error(group, variable, real_text(radius)//' ('//trim(shape)//' '//trim(adjustl(cells_text))// &
        ' cells thin on this grid)', 'a body at least 4 cells thick for the immersed boundary: &grid nx = ny = nz >= '// &
        int_text(ceiling(thinnest_cells * max(cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z) / &
        (2.0_wp * minval(semi_axes))))//remedy)
  end subroutine require_thick_enough

  !> A position given in a deck must lie in the periodic box of &grid, 0 <= x_d <= L_d: one outside
  !> would be wrapped to another place than the one written (a typo or a deck made for another box).
  subroutine require_in_box(group, variable, position, cfg)
    character(len=*), intent(in) :: group, variable
    real(wp), intent(in) :: position(3)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: box(3)
    integer :: d
    character(len=1), parameter :: axis(3) = ['x', 'y', 'z']
    box = [cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z]
    do d = 1, 3
      if (position(d) >= 0.0_wp .and. position(d) <= box(d)) cycle
      call input_error(group, variable, real_text(position(1))//', '//real_text(position(2))//', '// &
          real_text(position(3)), 'a position in the periodic box of &grid: 0 <= x <= length_x = '// &
          real_text(box(1))//' m, 0 <= y <= length_y = '//real_text(box(2))//' m, 0 <= z <= length_z = '// &
          real_text(box(3))//' m ('//axis(d)//' = '//real_text(position(d))//' m is outside; a position '// &
          'outside is not wrapped: give its image in the box)')
    end do
  end subroutine require_in_box

  !> Prescribed or free bodies: each centre at t = 0 in the box (they may leave it later, moving),
  !> whether the deck's arrays or the body file (named with the body's place among its bodies) gave it.
  subroutine check_bodies_in_box(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: n
    do n = 1, cfg%bodies%count
      if (len_trim(cfg%bodies%file) > 0) then
        call require_in_box('bodies', 'file "'//trim(cfg%bodies%file)//'", body '//int_text(n)//' (its centre)', &
                            cfg%bodies%centre(:, n), cfg)
      else
        call require_in_box('bodies', 'centre(:, '//int_text(n)//')', cfg%bodies%centre(:, n), cfg)
      end if
    end do
  end subroutine check_bodies_in_box

  !> Every variable of every group, whether the scene uses it or not, through the configuration's own
  !> namelist output (so no variable can be left out): each number finite (a NaN passes every
  !> "> 0" test written as .not. (x > 0) but not every other, and +Inf passes "> 0"), each text
  !> shorter than its variable (a namelist read cuts a longer value without a word).
  subroutine check_every_value(cfg)
    type(agglo_config_t), intent(in) :: cfg
    type(namelist_item_t), allocatable :: items(:)
    integer :: k, n
    items = config_items(cfg)
    do k = 1, size(items)
      if (item_text_fills(items(k))) then
        n = len(item_text_values(items(k)))   ! the variable's length: the written text is padded to it
        call input_error(items(k)%group, items(k)%name, filling_text(item_text_values(items(k)), n), &
            'at most '//int_text(n - 1)//' characters')
      end if
      if (.not. item_is_finite(items(k))) call input_error(items(k)%group, items(k)%name, &
          squeeze(items(k)%value), 'finite numbers (no NaN or Infinity)')
    end do
  end subroutine check_every_value

  !> The first element that fills its variable (n characters), quoted and cut to 40 characters.
  function filling_text(values, n) result(text)
    character(len=*), intent(in) :: values(:)
    integer, intent(in) :: n
    character(len=:), allocatable :: text
    integer :: k
    text = ''
    do k = 1, size(values)
      if (values(k)(n:n) == ' ') cycle
      text = ''''//values(k)(1:min(n, 40))//merge('...''', '''   ', n > 40)
      text = trim(text)//' ('//int_text(n)//' characters or more)'
      return
    end do
  end function filling_text

  !> The text with runs of blanks shortened to one blank, none after a repeat count ("3*NaN").
  pure function squeeze(text) result(out)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: out
    integer :: i
    out = ''
    do i = 1, len_trim(text)
      if (text(i:i) == ' ' .and. i > 1) then
        if (text(i - 1:i - 1) == ' ' .or. text(i - 1:i - 1) == '*') cycle
      end if
      out = out//text(i:i)
    end do
    out = trim(adjustl(out))
  end function squeeze

  !> What the scene switches on must fit together; checked before the groups' own values, so the
  !> first message names the real conflict (e.g. forcing in a pair deck), not a consequence of it.
  subroutine check_scene_combinations(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: interval
    if (cfg%scene%forcing /= 'none' .and. cfg%scene%fluid /= 'resolved') call input_error('scene', 'forcing', &
        ''''//trim(cfg%scene%forcing)//''' with fluid = '''//trim(cfg%scene%fluid)//'''', '''none'' unless '// &
        'fluid = ''resolved'' (the forcing drives the resolved fluid; a fluid-free or Stokes scene has no '// &
        'velocity field)')
    if (cfg%scene%fluid == 'resolved' .and. free_particles(cfg)) call check_resolved_pair_cross(cfg)
    if (cfg%scene%added_mass .and. .not. (cfg%scene%fluid == 'resolved' .and. free_particles(cfg))) &
      call input_error('scene', 'added_mass', '.true. with fluid = '''//trim(cfg%scene%fluid)//''' and particles = '''// &
                       trim(cfg%scene%particles)//'''', '.false. (the added mass belongs to particle_coupling = '// &
                       '''point'' or ''resolved'' of the pair in the resolved fluid)')
    if (cfg%scene%added_mass_history .and. .not. (cfg%scene%added_mass .and. cfg%scene%particle_coupling == 'resolved' &
        .and. cfg%fluid%viscous_scheme == 'explicit')) call input_error('scene', 'added_mass_history', '.true.', &
        '.false. unless added_mass = .true., particle_coupling = ''resolved'' and &fluid viscous_scheme = ''explicit'' '// &
        '(the history estimate of the stabilisation; with crank_nicolson it is always taken)')
    if (cfg%pair%relative_to_fluid .and. cfg%scene%fluid /= 'resolved') call input_error('pair', &
        'relative_to_fluid', '.true. with &scene fluid = '''//trim(cfg%scene%fluid)//'''', '.false. (only a '// &
        'resolved fluid has a velocity at the particle centres)')
    if (cfg%pair%hydrodynamics_from /= 'start' .and. cfg%scene%fluid == 'none') call input_error('pair', &
        'hydrodynamics_from', ''''//trim(cfg%pair%hydrodynamics_from)//''' with &scene fluid = ''none''', &
        '''start'' (without a fluid there are no hydrodynamic loads to switch on)')
    if (any(cfg%pair%gravity /= 0.0_wp) .and. .not. (cfg%scene%fluid == 'resolved' .and. free_particles(cfg) &
        .and. cfg%scene%particle_coupling == 'resolved')) call input_error('pair', 'gravity', 'non-zero without '// &
        '&scene fluid = ''resolved'', particles = ''pair'', particle_coupling = ''resolved''', '0, 0, 0 (gravity '// &
        'acts on the particles resolved by the immersed boundary only)')
    if (cfg%scene%particles == 'prescribed') call check_prescribed_cross(cfg)
    if (cfg%scene%particles == 'free') call check_free_cross(cfg)
    if (cfg%scene%fluid /= 'resolved' .and. cfg%scene%particles == 'none') call input_error('scene', &
        'particles', '''none'' with fluid = '''//trim(cfg%scene%fluid)//'''', &
        '''pair'' (a fluid-free or Stokes scene has nothing to compute without particles)')
    if (cfg%scene%fluid /= 'resolved' .and. cfg%run%dt_mode /= 'fixed') call input_error('run', 'dt_mode', &
        ''''//trim(cfg%run%dt_mode)//''' with fluid = '''//trim(cfg%scene%fluid)//'''', &
        '''fixed'' (the CFL number is a property of the resolved fluid)')
    if (cfg%scene%fluid /= 'resolved' .and. cfg%scene%particle_substeps /= 1) call input_error('scene', &
        'particle_substeps', int_text(cfg%scene%particle_substeps)//' with fluid = '''//trim(cfg%scene%fluid)//'''', &
        '1 (sub-steps split a fluid step; without a resolved fluid set &run dt itself)')
    if (cfg%scene%substep_bodies == 'near' .and. .not. (cfg%scene%fluid == 'resolved' .and. &
        cfg%scene%particles == 'suspension' .and. cfg%scene%particle_coupling == 'point')) &
      call input_error('scene', 'substep_bodies', '''near'' with fluid = '''//trim(cfg%scene%fluid)// &
          ''', particles = '''//trim(cfg%scene%particles)//''', particle_coupling = '''// &
          trim(cfg%scene%particle_coupling)//'''', '''all'' (''near'' needs fluid = ''resolved'', particles = '// &
          '''suspension'' and particle_coupling = ''point'': the one-step update of the other bodies is the '// &
          'point particle''s)')
    ! With 'near' the bodies of the one-step update are at the fluid step's end from its start on:
    ! a particles.h5 row belongs on a fluid-step boundary.
    if (cfg%scene%substep_bodies == 'near') then
      interval = cfg%output%particle_interval
      if (interval == 0) interval = cfg%output%stats_interval
      if (mod(interval, cfg%scene%particle_substeps) /= 0) call input_error('output', 'particle_interval', &
          int_text(interval)//' (or stats_interval when 0) with &scene substep_bodies = ''near''', &
          'a multiple of &scene particle_substeps = '//int_text(cfg%scene%particle_substeps)// &
          ' (rows on fluid-step boundaries, where every body is at the same time)')
    end if
  end subroutine check_scene_combinations

  !> The pair in the resolved fluid: the immersed-boundary coupling ('resolved') imposes the bodies
  !> with the immersed boundary, with either viscous scheme (with Crank-Nicolson the predictor's
  !> system holds the body rows, docs/theory.md "Crank-Nicolson with free particles"); particles at
  !> least half as dense as the fluid (below, the added-mass stabilisation of a disk's rotation was
  !> measured to ring with a growing amplitude, docs/studies/validation.md "Free particles").
  subroutine check_resolved_pair_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    if (cfg%scene%particle_coupling == 'resolved' .and. cfg%pair%density < 0.5_wp * cfg%fluid%density) &
      call input_error('pair', 'density', real_text(cfg%pair%density), '>= 0.5 x &fluid density = '// &
                       real_text(0.5_wp * cfg%fluid%density)//' with &scene particle_coupling = ''resolved'' (lighter '// &
                       'particles are not stable with the lagged loads, docs/studies/validation.md "Free particles")')
  end subroutine check_resolved_pair_cross

  !> The pair in the resolved fluid's periodic box: a given pair centre in the box; body 2's minimum
  !> image must be the one next to body 1.
  subroutine check_pair_in_box(cfg)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: reach, smallest
    ! The longest semi-axis is at most r max(a/b, b/a)**(2/3) (a b^2 = r^3, spheroid.f90).
    reach = cfg%pair%radius
    if (cfg%pair%shape /= 'sphere') &
      reach = reach * max(cfg%pair%aspect_ratio, 1.0_wp / cfg%pair%aspect_ratio)**(2.0_wp / 3.0_wp)
    smallest = min(cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z)
    ! The pair is handled as body 2's minimum image next to body 1: their centres, at most
    ! 2 reach + gap apart while they interact, must stay within half a box length.
    if (.not. (2.0_wp * reach + cfg%pair%gap < 0.5_wp * smallest)) call input_error('pair', 'radius', &
        real_text(cfg%pair%radius), 'a pair whose centres, 2 x the longest semi-axis ('//real_text(reach)// &
        ' m) plus the gap apart, are less than half the smallest box length ('//real_text(smallest)// &
        ' m) apart (the minimum-image convention of the periodic box)')
    ! Then where it is (a pair too large for the box is the more basic error).
    if (cfg%pair%centre == 'given') call require_in_box('pair', 'centre_position', cfg%pair%centre_position, cfg)
  end subroutine check_pair_in_box

  !> The scene's particles move under their loads (the pair, or free bodies placed by &bodies).
  logical function free_particles(cfg)
    type(agglo_config_t), intent(in) :: cfg
    free_particles = cfg%scene%particles == 'pair' .or. cfg%scene%particles == 'free' .or. &
                     cfg%scene%particles == 'suspension'
  end function free_particles

  !> Free bodies placed by &bodies: in the resolved fluid (the point or resolved provider), starting
  !> with the deck's velocities; an oscillation is prescribed motion, which free bodies do not have.
  subroutine check_free_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: n
    if (cfg%scene%fluid /= 'resolved') call input_error('scene', 'particles', '''free'' with fluid = '''// &
        trim(cfg%scene%fluid)//'''', 'fluid = ''resolved'' (free bodies of any count run in the resolved fluid; '// &
        'fluid-free and Stokes scenes run the pair)')
    do n = 1, cfg%bodies%count
      if (any(cfg%bodies%oscillation_amplitude(:, n) /= 0.0_wp) .or. cfg%bodies%oscillation_frequency(n) /= 0.0_wp) &
        call input_error('bodies', 'oscillation_frequency('//int_text(n)//')', &
                         real_text(cfg%bodies%oscillation_frequency(n))//' (or a non-zero oscillation_amplitude)', &
                         '0 with &scene particles = ''free'' (free bodies move under their loads, not a prescribed motion)')
    end do
  end subroutine check_free_cross

  !> A suspension in the periodic box of &grid: each species' longest extent (2 a or 2 b) plus
  !> min_gap under half the smallest box length (the minimum-image convention of the pairs); the
  !> nanometre-scale model lengths far below the smallest body (the Derjaguin limit, as for the
  !> pair); min_gap above the collision detection floor (a body placed inside the detection distance
  !> would collide at the first step). The thickness the immersed boundary needs is checked with the
  !> other bodies' (check_bodies_thick_enough).
  subroutine check_suspension_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: axes(2), smallest_box, smallest_radius
    integer :: k
    character(len=:), allocatable :: index
    smallest_box = min(cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z)
    smallest_radius = huge(1.0_wp)
    do k = 1, species_count(cfg%suspension)
      index = '('//int_text(k)//')'
      axes = species_semi_axes(cfg%suspension, k)
      smallest_radius = min(smallest_radius, minval(axes))
      if (.not. (2.0_wp * maxval(axes) + cfg%suspension%min_gap < 0.5_wp * smallest_box)) call input_error( &
          'suspension', 'radius'//index, real_text(cfg%suspension%radius(k)), 'a body whose longest extent 2 x '// &
          real_text(maxval(axes))//' m plus min_gap is under half the smallest box length ('// &
          real_text(0.5_wp * smallest_box)//' m; the minimum-image convention of the periodic box)')
    end do
    if (cfg%scene%dlvo .and. .not. cfg%suspension%ghost) then
      if (.not. (cfg%dlvo%vdw_cutoff < 0.01_wp * smallest_radius)) call input_error('dlvo', 'vdw_cutoff', &
          real_text(cfg%dlvo%vdw_cutoff), '< 0.01 x the smallest semi-axis of &suspension = '// &
          real_text(0.01_wp * smallest_radius)//' m')
    end if
    if (cfg%scene%collisions) then
      if (.not. (cfg%suspension%min_gap > cfg%collision%detection_floor)) call input_error('suspension', 'min_gap', &
          real_text(cfg%suspension%min_gap), '> &collision detection_floor = '// &
          real_text(cfg%collision%detection_floor)//' m (a body placed within it collides at the first step)')
    end if
    if (cfg%suspension%ghost .and. cfg%collision%lubrication) call input_error('suspension', 'ghost', &
        '.true. with &collision lubrication = .true.', '.false., or lubrication = .false. (ghost bodies pass '// &
        'through each other; a lubrication force would act between them)')
    if (cfg%suspension%ghost .and. .not. cfg%scene%collisions) call input_error('suspension', 'ghost', &
        '.true. with &scene collisions = .false.', '.false., or &scene collisions = .true. (ghost mode counts '// &
        'the collisions the collision test detects)')
  end subroutine check_suspension_cross

  !> Bodies in prescribed motion: resolved fluid (either viscous scheme: with Crank-Nicolson the
  !> predictor's system holds the body rows, immersed_predictor; any forcing).
  subroutine check_prescribed_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    if (cfg%scene%fluid /= 'resolved') call input_error('scene', 'particles', '''prescribed'' with fluid = '''// &
        trim(cfg%scene%fluid)//'''', 'fluid = ''resolved'' (bodies in prescribed motion need the resolved fluid)')
  end subroutine check_prescribed_cross

  !> Resolved fluid: the grid must split into equal slabs along z and y (pencil transposes of the FFT).
  subroutine check_fluid_cross(cfg, nranks)
    type(agglo_config_t), intent(in) :: cfg
    integer, intent(in) :: nranks
    if (mod(cfg%grid%nz, nranks) /= 0) call input_error('grid', 'nz', int_text(cfg%grid%nz), &
        'a multiple of the number of MPI ranks ('//int_text(nranks)//')')
    if (mod(cfg%grid%ny, nranks) /= 0) call input_error('grid', 'ny', int_text(cfg%grid%ny), &
        'a multiple of the number of MPI ranks ('//int_text(nranks)//')')
    call check_fluid_time_step(cfg)
    if (cfg%fluid%init == 'random') call check_random_peak(cfg)
  end subroutine check_fluid_cross

  !> The random field's spectral peak k_p = init_peak_wavenumber 2 pi / length_x must be resolved:
  !> at most the smallest Nyquist wavenumber pi n_d / L_d of the grid, i.e.
  !> init_peak_wavenumber <= min_d n_d length_x / (2 L_d). Above it the spectrum is cut before its
  !> peak and the field is not the one the deck describes.
  subroutine check_random_peak(cfg)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: nyquist
    nyquist = min(cfg%grid%nx * cfg%grid%length_x / (2.0_wp * cfg%grid%length_x), &
                  cfg%grid%ny * cfg%grid%length_x / (2.0_wp * cfg%grid%length_y), &
                  cfg%grid%nz * cfg%grid%length_x / (2.0_wp * cfg%grid%length_z))
    if (.not. (cfg%fluid%init_peak_wavenumber <= nyquist)) call input_error('fluid', 'init_peak_wavenumber', &
        real_text(cfg%fluid%init_peak_wavenumber), '<= '//real_text(nyquist)//', the grid''s smallest Nyquist '// &
        'wavenumber min(n_d length_x / (2 L_d)) in units of 2 pi / length_x (refine &grid or lower the peak)')
  end subroutine check_random_peak

  !> A fixed dt must be below the stability limits the initial field lets us estimate:
  !>  - explicit diffusion (AB2, 7-point Laplacian): dt <= 1 / (4 nu (1/dx^2 + 1/dy^2 + 1/dz^2))
  !>    (the same bound as time_step_control's explicit_viscous_limit; config cannot use fluid/);
  !>  - advection: dt (Ux/dx + Uy/dy + Uz/dz) <= cfl_limit with the peak velocity estimated from
  !>    the initial amplitude U: Taylor-Green peaks are exactly (U, U lx/ly, 0); a random field's
  !>    peak is taken as 3 U per component (about the 99.9th percentile of a Gaussian component).
  !> With dt_mode = 'cfl' dt is only the largest step and the run adapts it, so only explicit
  !> diffusion is checked there (the run applies cfl_target times that bound too).
  subroutine check_fluid_time_step(cfg)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: dx, dy, dz, viscous_limit, peak(3), advective_limit
    dx = cfg%grid%length_x / cfg%grid%nx; dy = cfg%grid%length_y / cfg%grid%ny; dz = cfg%grid%length_z / cfg%grid%nz
    if (cfg%fluid%viscous_scheme == 'explicit' .and. cfg%run%dt_mode == 'fixed') then
      viscous_limit = 1.0_wp / (4.0_wp * cfg%fluid%viscosity * (1.0_wp / dx**2 + 1.0_wp / dy**2 + 1.0_wp / dz**2))
      if (cfg%run%dt > viscous_limit) call input_error('run', 'dt', real_text(cfg%run%dt), &
          '<= '//real_text(viscous_limit)//' s, the stability limit of explicit diffusion on this grid '// &
          '(or set &fluid viscous_scheme = ''crank_nicolson'', or dt_mode = ''cfl'')')
    end if
    if (cfg%run%dt_mode /= 'fixed') return
    select case (trim(cfg%fluid%init))
    case ('taylor_green')
      peak = cfg%fluid%init_amplitude * [1.0_wp, cfg%grid%length_y / cfg%grid%length_x, 0.0_wp]
    case ('random')
      peak = 3.0_wp * cfg%fluid%init_amplitude
    case default
      return   ! rest: nothing to estimate; file: checked at run time by the CFL monitor
    end select
    if (all(peak == 0.0_wp)) return
    advective_limit = cfg%run%cfl_limit / (peak(1) / dx + peak(2) / dy + peak(3) / dz)
    if (cfg%run%dt > advective_limit) call input_error('run', 'dt', real_text(cfg%run%dt), &
        '<= '//real_text(advective_limit)//' s, the advective limit cfl_limit / (Ux/dx + Uy/dy + Uz/dz) '// &
        'for the estimated peak velocity of the initial field (or set dt_mode = ''cfl'')')
  end subroutine check_fluid_time_step

  !> Forcing: only of a resolved fluid; the forced modes must be representable on the grid; the
  !> Euler-Maruyama form (paper Eq. 3) needs dt <= T_L (its decay factor 1 - dt/T_L turns negative).
  subroutine check_forcing_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: extent(3), cells(3), d
    real(wp) :: lengths(3)
    character(len=1), parameter :: axis(3) = ['x', 'y', 'z']
    lengths = [cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z]
    cells = [cfg%grid%nx, cfg%grid%ny, cfg%grid%nz]
    extent = forcing_mode_extent(cfg%forcing%kappa_f_ratio, lengths)
    do d = 1, 3
      if (2 * extent(d) >= cells(d)) call input_error('forcing', 'kappa_f_ratio', &
          real_text(cfg%forcing%kappa_f_ratio), 'a cut-off whose modes lie below the grid''s Nyquist '// &
          'wavenumber: it forces |n_'//axis(d)//'| up to '//int_text(extent(d))//', which needs n'//axis(d)// &
          ' > '//int_text(2 * extent(d))//' cells (n'//axis(d)//' = '//int_text(cells(d))//')')
    end do
    if (cfg%forcing%update == 'euler_maruyama' .and. cfg%run%dt > cfg%forcing%time_scale) call input_error( &
        'forcing', 'update', '''euler_maruyama'' with &run dt = '//real_text(cfg%run%dt)//' s > time_scale = '// &
        real_text(cfg%forcing%time_scale)//' s', '''exact'' (any dt), or euler_maruyama with dt <= time_scale')
  end subroutine check_forcing_cross

  !> Particle models: the nanometre-scale lengths must be far below the particle size (the DLVO and
  !> collision models are surface-gap models in the Derjaguin limit, h << r).
  subroutine check_particle_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    real(wp) :: detect
    if (cfg%scene%dlvo) then
      if (.not. (cfg%dlvo%vdw_cutoff < 0.01_wp * cfg%pair%radius)) call input_error('dlvo', 'vdw_cutoff', &
          real_text(cfg%dlvo%vdw_cutoff), '< 0.01 * &pair radius = '//real_text(0.01_wp * cfg%pair%radius)//' m')
    end if
    if (cfg%scene%collisions) then
      if (.not. (cfg%collision%detection_floor < 0.01_wp * cfg%pair%radius)) call input_error('collision', &
          'detection_floor', real_text(cfg%collision%detection_floor), &
          '< 0.01 * &pair radius = '//real_text(0.01_wp * cfg%pair%radius)//' m')
      ! A start inside the detection distance max(floor, factor v_n dt) (collision.f90; v_n = the
      ! approach speed at the start) is a collision at the first step, whose outcome depends on dt.
      detect = max(cfg%collision%detection_floor, cfg%collision%detection_factor * cfg%pair%relative_speed * cfg%run%dt &
                                                  / cfg%scene%particle_substeps)   ! the particle step
      if (.not. (cfg%pair%gap > detect)) call input_error('pair', 'gap', real_text(cfg%pair%gap), '> '// &
          real_text(detect)//' m, the collision detection distance at the start, max(&collision '// &
          'detection_floor, detection_factor * relative_speed * &run dt / &scene particle_substeps)')
    end if
    if (cfg%collision%lubrication) then
      if (cfg%scene%fluid == 'none') call input_error('collision', 'lubrication', '.true. with &scene fluid = ''none''', &
          '.false. (no fluid, no lubrication), or &scene fluid = ''stokes'' | ''resolved''')
      if (.not. (cfg%collision%lubrication_roughness < cfg%collision%lubrication_handover * smallest_spacing(cfg%grid))) &
        call input_error('collision', 'lubrication_roughness', real_text(cfg%collision%lubrication_roughness), &
          '< the hand-over gap lubrication_handover * &grid spacing = '// &
          real_text(cfg%collision%lubrication_handover * smallest_spacing(cfg%grid))//' m')
    else if (cfg%collision%lubrication_tangential) then
      call input_error('collision', 'lubrication_tangential', '.true. with lubrication = .false.', &
          '.false., or lubrication = .true. (the tangential terms belong to the sub-grid lubrication model)')
    end if
  end subroutine check_particle_cross

end module config_checks
