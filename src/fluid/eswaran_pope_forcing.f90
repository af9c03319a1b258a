!> Eswaran & Pope (1988) stochastic forcing, as described by Chouippe & Uhlmann (2015) and the
!> paper (section 2.1, Eqs. 2-6); docs/physics.md section 3.
!>
!>   f(x,t) = sum_{0 < |k| <= kappa_F} f^(k,t) exp(i k.x),   k = (2 pi n1/Lx, 2 pi n2/Ly, 2 pi n3/Lz)
!>
!> Only one wavevector of each +-k pair is evolved (the "half set": n1 > 0, or n1 = 0 and n2 > 0, or
!> n1 = n2 = 0 and n3 > 0); f^(-k) = conj(f^(k)) makes the field real (Hermitian completion), so
!> f(x) = sum_{half set} 2 Re(f^(k) exp(i k.x)). Each Cartesian component of b^(k) has a real and an
!> imaginary part, each an independent Ornstein-Uhlenbeck process of variance sigma^2 and time scale
!> T_L (so <b_i b_j^*> = 2 sigma^2 delta_ij, Eq. 6). f^ = b^ - k (k.b^)/|k|^2 (Eq. 4).
!>
!> Evaluation: each velocity component at its own MAC face positions (u at (i dx, (j-1/2)dy, (k-1/2)dz),
!> v at ((i-1/2)dx, j dy, (k-1/2)dz), w at ((i-1/2)dx, (j-1/2)dy, k dz)) by separable direct sums
!> with precomputed 1-D factors exp(i 2 pi n x/L): per z plane the modes are collapsed onto an
!> (n1, n2) table, per row onto n1, and per point only the few n1 >= 0 remain; no FFT is needed.
!> The 1-D factors depend on the global index only and every sum runs in a fixed order, so the
!> forcing values are bit for bit the same whatever the number of ranks.
!>
!> Random numbers: one stream (random_stream, stream id 2, seeded from &run seed) that every rank
!> advances identically (no communication). Draw order per step: modes in the half-set order,
!> components x, y, z, real part then imaginary part.
module eswaran_pope_forcing
  use, intrinsic :: iso_c_binding, only: c_double
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use config_forcing, only: forcing_config_t, forcing_strength_input, forcing_mode_extent, cutoff_slack
  use random_stream, only: random_stream_t, stream_seed, stream_normal, stream_pack, stream_unpack, &
                           stream_state_size
  use error_handling, only: fatal
  use text_format, only: real_text, int_text
  use logger, only: log_line
  use parallel_env, only: global_sum
  use fluid_grid, only: fluid_grid_t
  implicit none
  private
  public :: ep_forcing_t, forcing_init, forcing_init_on_grid, forcing_advance, forcing_add_to, forcing_set_field, &
            forcing_set_fields, &
            forcing_power_input, forcing_state_size, forcing_pack_state, forcing_unpack_state, &
            forcing_restore_coefficients, &
            forcing_mode_extent, forcing_mode_is_forced, ep_power_estimate, epsilon_star_for_dissipation, &
            forcing_pair_count, forcing_mode_integers, forcing_wavevectors, forcing_coefficients, &
            forcing_projected, forcing_sigma, forcing_epsilon_star, forcing_time_scale, forcing_kappa0
  public :: forcing_stream_id, update_exact, update_euler_maruyama

  integer, parameter :: forcing_stream_id = 2          !< docs/design.md, "Conventions": stream 2 = forcing
  integer, parameter :: update_exact = 1, update_euler_maruyama = 2
  !> E&P (1988) finite-T_L estimate constant (docs/physics.md section 3).
  real(wp), parameter :: ep_constant = 0.8_wp
  integer(i8), parameter :: state_format = 20250301_i8   !< first word of a packed state
  integer, parameter :: state_header = 4                 !< format, pairs, update kind, steps

  integer, parameter :: at_face = 1, at_centre = 2       !< position of a component along one axis

  type :: ep_forcing_t
    private
    logical :: ready = .false.
    integer :: update_kind = update_exact
    real(wp) :: time_scale = 0.0_wp      !< s, T_L
    real(wp) :: sigma = 0.0_wp           !< m/s^2, standard deviation of each real OU process
    real(wp) :: epsilon_star = 0.0_wp    !< m^2/s^3, sigma^2 T_L
    real(wp) :: kappa0 = 0.0_wp          !< 1/m, 2 pi / (largest box length)
    integer :: n_pairs = 0               !< evolved wavevectors (half of the forced set)
    integer(i8) :: steps = 0_i8          !< OU updates done since the start of the run
    integer :: mode_extent(3) = 0        !< largest |n_d| of any forced mode
    integer, allocatable :: modes(:,:)           !< (3, n_pairs) integer vectors n
    real(wp), allocatable :: wavevector(:,:)     !< (3, n_pairs) k, 1/m
    complex(wp), allocatable :: b_hat(:,:)       !< (3, n_pairs) OU coefficients b^, m/s^2
    complex(wp), allocatable :: f_hat(:,:)       !< (3, n_pairs) projected coefficients f^ (Eq. 4)
    type(random_stream_t) :: stream
    ! The local slab and the 1-D factors exp(i 2 pi n x / L) at faces and centres.
    integer :: nx = 0, ny = 0, nz = 0, nz_local = 0, z_offset = 0
    real(wp), allocatable :: ex_re(:,:,:), ex_im(:,:,:)   !< (nx, 0:m1, face|centre)
    complex(wp), allocatable :: ey(:,:,:)                 !< (-m2:m2, ny, face|centre)
    complex(wp), allocatable :: ez(:,:,:)                 !< (-m3:m3, nz_local, face|centre)
  end type ep_forcing_t

  interface
    !> C99 expm1: 1 - exp(-2 dt/T_L) without cancellation for dt << T_L.
    pure function c_expm1(x) bind(c, name='expm1') result(y)
      import :: c_double
      real(c_double), value :: x
      real(c_double) :: y
    end function c_expm1
  end interface

contains

  ! ------------------------------------------------------------------ set-up

  !> 0 < |k| <= kappa_F for the integer vector n (in units of kappa0 = 2 pi / L_max).
  pure logical function forcing_mode_is_forced(n, kappa_f_ratio, lengths)
    integer, intent(in) :: n(3)
    real(wp), intent(in) :: kappa_f_ratio, lengths(3)
    real(wp) :: k_over_kappa0_squared
    k_over_kappa0_squared = sum((real(n, wp) * maxval(lengths) / lengths)**2)
    forcing_mode_is_forced = any(n /= 0) .and. &
        k_over_kappa0_squared <= kappa_f_ratio**2 * (1.0_wp + cutoff_slack)**2
  end function forcing_mode_is_forced

  !> E&P (1988) estimate of the mean energy input (docs/physics.md section 3), m^2/s^3:
  !> eps_T = 4 eps* N_F / (1 + T_L* N_F^(1/3) / 0.8), T_L* = T_L eps*^(1/3) kappa0^(2/3);
  !> N_F counts +k and -k. Without the denominator it is the white-noise (T_L -> 0) limit.
  pure function ep_power_estimate(epsilon_star, time_scale, kappa0, n_forced) result(power)
    real(wp), intent(in) :: epsilon_star, time_scale, kappa0
    integer, intent(in) :: n_forced
    real(wp) :: power, time_scale_star
    time_scale_star = time_scale * epsilon_star**(1.0_wp / 3.0_wp) * kappa0**(2.0_wp / 3.0_wp)
    power = 4.0_wp * epsilon_star * n_forced / (1.0_wp + time_scale_star * n_forced**(1.0_wp / 3.0_wp) / ep_constant)
  end function ep_power_estimate

  !> Inverse of ep_power_estimate: the epsilon* whose E&P estimate is the target dissipation.
  !> With x = eps*^(1/3): g(x) = 4 N x^3 - eps_T (1 + c x) = 0, c = T_L kappa0^(2/3) N^(1/3) / 0.8.
  !> g is convex on x > 0 with g(0) < 0, so the positive root is unique and Newton's method from
  !> x0 = (eps_T/4N)^(1/3) + (eps_T c/4N)^(1/2) (where g(x0) >= 0) decreases monotonically onto it.
  pure function epsilon_star_for_dissipation(target, time_scale, kappa0, n_forced) result(epsilon_star)
    real(wp), intent(in) :: target, time_scale, kappa0
    integer, intent(in) :: n_forced
    real(wp) :: epsilon_star, c, x, step
    integer :: iteration
    c = time_scale * kappa0**(2.0_wp / 3.0_wp) * n_forced**(1.0_wp / 3.0_wp) / ep_constant
    x = (target / (4.0_wp * n_forced))**(1.0_wp / 3.0_wp) + sqrt(target * c / (4.0_wp * n_forced))
    do iteration = 1, 200
      step = (4.0_wp * n_forced * x**3 - target * (1.0_wp + c * x)) / (12.0_wp * n_forced * x**2 - target * c)
      x = x - step
      if (abs(step) <= 4.0_wp * epsilon(1.0_wp) * x) exit
    end do
    epsilon_star = x**3
  end function epsilon_star_for_dissipation

  !> Set up the forcing on the local slab: the forced modes, sigma and epsilon*, the stream, the
  !> initial OU state (drawn from the stationary distribution N(0, sigma^2), so the forcing is
  !> statistically stationary from the first step) and the 1-D factors. Collective only in the
  !> sense that every rank must call it with the same deck; no communication.
  !> n(3) = global cells, lengths(3) = box (m), nz_local/z_offset = this rank's slab along z.
  subroutine forcing_init(self, cfg, seed, n, lengths, nz_local, z_offset)
    type(ep_forcing_t), intent(out) :: self
    type(forcing_config_t), intent(in) :: cfg
    integer, intent(in) :: seed
    integer, intent(in) :: n(3), nz_local, z_offset
    real(wp), intent(in) :: lengths(3)
    character(len=:), allocatable :: strength_source
    integer :: n1, n2, n3, m, c, count_pairs
    real(wp) :: power_limit, power_estimate, time_scale_star

    self%time_scale = cfg%time_scale
    self%kappa0 = two_pi / maxval(lengths)
    self%mode_extent = forcing_mode_extent(cfg%kappa_f_ratio, lengths)
    if (any(2 * self%mode_extent >= n)) call fatal('forcing: kappa_F = '//real_text(cfg%kappa_f_ratio)// &
        ' kappa0 reaches the Nyquist wavenumber of the grid (needs 2 |n_d| < cells along each axis)')
    select case (trim(cfg%update))
    case ('exact')
      self%update_kind = update_exact
    case ('euler_maruyama')
      self%update_kind = update_euler_maruyama
    case default
      call fatal('forcing: unknown update '''//trim(cfg%update)//'''')
    end select

    ! The half set, in a fixed order (n3, then n2, then n1 ascending).
    count_pairs = 0
    do m = 1, 2
      if (m == 2) allocate(self%modes(3, count_pairs), self%wavevector(3, count_pairs))
      count_pairs = 0
      do n3 = -self%mode_extent(3), self%mode_extent(3)
        do n2 = -self%mode_extent(2), self%mode_extent(2)
          do n1 = 0, self%mode_extent(1)
            if (.not. in_half_set([n1, n2, n3])) cycle
            if (.not. forcing_mode_is_forced([n1, n2, n3], cfg%kappa_f_ratio, lengths)) cycle
            count_pairs = count_pairs + 1
            if (m == 2) then
              self%modes(:, count_pairs) = [n1, n2, n3]
              self%wavevector(:, count_pairs) = two_pi * real([n1, n2, n3], wp) / lengths
            end if
          end do
        end do
      end do
    end do
    self%n_pairs = count_pairs
    if (self%n_pairs == 0) call fatal('forcing: no wavevector with 0 < |k| <= kappa_F')

    strength_source = forcing_strength_input(cfg)
    select case (strength_source)
    case ('sigma')
      self%sigma = cfg%sigma
      self%epsilon_star = cfg%sigma**2 * cfg%time_scale
    case ('epsilon_star')
      self%epsilon_star = cfg%epsilon_star
      self%sigma = sqrt(cfg%epsilon_star / cfg%time_scale)
    case ('target_dissipation')
      self%epsilon_star = epsilon_star_for_dissipation(cfg%target_dissipation, cfg%time_scale, self%kappa0, &
                                                       2 * self%n_pairs)
      self%sigma = sqrt(self%epsilon_star / cfg%time_scale)
    case default
      call fatal('forcing: give exactly one of &forcing sigma, epsilon_star, target_dissipation')
    end select

    call stream_seed(self%stream, int(seed, i8), forcing_stream_id)
    allocate(self%b_hat(3, self%n_pairs), self%f_hat(3, self%n_pairs))
    do m = 1, self%n_pairs
      do c = 1, 3
        self%b_hat(c, m) = self%sigma * next_complex_normal(self%stream)
      end do
    end do
    self%steps = 0_i8
    call project(self)
    call build_factors(self, n, nz_local, z_offset)
    self%ready = .true.

    power_limit = 4.0_wp * self%epsilon_star * (2 * self%n_pairs)
    power_estimate = ep_power_estimate(self%epsilon_star, self%time_scale, self%kappa0, 2 * self%n_pairs)
    time_scale_star = self%time_scale * self%epsilon_star**(1.0_wp / 3.0_wp) * self%kappa0**(2.0_wp / 3.0_wp)
    call log_line('forcing: Eswaran-Pope, N_F = '//int_text(2 * self%n_pairs)//' wavevectors ('// &
        int_text(self%n_pairs)//' +-k pairs) with 0 < |k| <= kappa_F = '//real_text(cfg%kappa_f_ratio)// &
        ' kappa0, kappa0 = '//real_text(self%kappa0)//' 1/m; update '''//trim(cfg%update)//'''')
    call log_line('forcing: T_L = '//real_text(self%time_scale)//' s, sigma = '//real_text(self%sigma)// &
        ' m/s^2, epsilon* = sigma^2 T_L = '//real_text(self%epsilon_star)//' m^2/s^3 (from '// &
        strength_source//')')
    call log_line('forcing: E&P power estimate '//real_text(power_estimate)//' m^2/s^3 (T_L* = '// &
        real_text(time_scale_star)//'); white-noise limit 4 N_F epsilon* = '//real_text(power_limit)//' m^2/s^3')
  end subroutine forcing_init

  !> forcing_init on the fluid's grid and slab.
  subroutine forcing_init_on_grid(self, cfg, seed, grid)
    type(ep_forcing_t), intent(out) :: self
    type(forcing_config_t), intent(in) :: cfg
    integer, intent(in) :: seed
    type(fluid_grid_t), intent(in) :: grid
    call forcing_init(self, cfg, seed, [grid%nx, grid%ny, grid%nz], [grid%lx, grid%ly, grid%lz], &
                      grid%nz_local, grid%z_offset)
  end subroutine forcing_init_on_grid

  pure logical function in_half_set(n)
    integer, intent(in) :: n(3)
    in_half_set = n(1) > 0 .or. (n(1) == 0 .and. n(2) > 0) .or. (n(1) == 0 .and. n(2) == 0 .and. n(3) > 0)
  end function in_half_set

  !> exp(i 2 pi n x / L) at face (x = i dx) and centre (x = (i - 1/2) dx) positions. The phase is
  !> reduced exactly in integers, n (2 i - s) mod 2N, so every rank gets the same bits for the
  !> same global index.
  subroutine build_factors(self, n, nz_local, z_offset)
    type(ep_forcing_t), intent(inout) :: self
    integer, intent(in) :: n(3), nz_local, z_offset
    integer :: i, mode, at
    complex(wp) :: factor
    self%nx = n(1); self%ny = n(2); self%nz = n(3)
    self%nz_local = nz_local; self%z_offset = z_offset
    associate (m1 => self%mode_extent(1), m2 => self%mode_extent(2), m3 => self%mode_extent(3))
      allocate(self%ex_re(n(1), 0:m1, 2), self%ex_im(n(1), 0:m1, 2))
      allocate(self%ey(-m2:m2, n(2), 2), self%ez(-m3:m3, nz_local, 2))
      do at = at_face, at_centre
        do mode = 0, m1
          do i = 1, n(1)
            factor = unit_phase(mode, i, n(1), at)
            self%ex_re(i, mode, at) = real(factor, wp)
            self%ex_im(i, mode, at) = aimag(factor)
          end do
        end do
        do i = 1, n(2)
          do mode = -m2, m2
            self%ey(mode, i, at) = unit_phase(mode, i, n(2), at)
          end do
        end do
        do i = 1, nz_local
          do mode = -m3, m3
            self%ez(mode, i, at) = unit_phase(mode, z_offset + i, n(3), at)
          end do
        end do
      end do
    end associate
  end subroutine build_factors

  pure function unit_phase(mode, index, cells, at) result(factor)
    integer, intent(in) :: mode, index, cells, at
    complex(wp) :: factor
    integer :: numerator
    real(wp) :: angle
    numerator = modulo(mode * (2 * index - merge(0, 1, at == at_face)), 2 * cells)
    angle = two_pi * real(numerator, wp) / real(2 * cells, wp)
    factor = cmplx(cos(angle), sin(angle), wp)
  end function unit_phase

  ! ------------------------------------------------------------------ time stepping

  !> Advance every OU process by dt (s), then project (Eq. 4). Same on every rank.
  !>   exact:           b <- b e^(-dt/T_L) + sigma sqrt(1 - e^(-2 dt/T_L)) xi   (any dt)
  !>   euler_maruyama:  b <- b (1 - dt/T_L) + xi sqrt(2 sigma^2 dt/T_L)         (paper Eq. 3)
  !> xi: independent N(0,1) for the real and the imaginary part.
  subroutine forcing_advance(self, dt)
    type(ep_forcing_t), intent(inout) :: self
    real(wp), intent(in) :: dt
    real(wp) :: ratio, decay, amplitude
    integer :: m, c
    if (.not. self%ready) call fatal('forcing_advance: the forcing is not set up', collective=.false.)
    if (.not. (dt > 0.0_wp)) call fatal('forcing_advance: dt = '//real_text(dt)//' s; needs dt > 0')
    ratio = dt / self%time_scale
    select case (self%update_kind)
    case (update_exact)
      decay = exp(-ratio)
      amplitude = self%sigma * sqrt(-c_expm1(-2.0_wp * ratio))
    case default
      if (ratio > 1.0_wp) call fatal('forcing: euler_maruyama update with dt = '//real_text(dt)// &
          ' s > T_L = '//real_text(self%time_scale)//' s (the factor 1 - dt/T_L of Eq. 3 turns negative); '// &
          'use &forcing update = ''exact'' or a smaller dt')
      decay = 1.0_wp - ratio
      amplitude = sqrt(2.0_wp * self%sigma**2 * ratio)
    end select
    do m = 1, self%n_pairs
      do c = 1, 3
        self%b_hat(c, m) = decay * self%b_hat(c, m) + amplitude * next_complex_normal(self%stream)
      end do
    end do
    self%steps = self%steps + 1_i8
    call project(self)
  end subroutine forcing_advance

  !> Real part then imaginary part, each N(0,1).
  function next_complex_normal(stream) result(z)
    type(random_stream_t), intent(inout) :: stream
    complex(wp) :: z
    real(wp) :: re, im
    re = stream_normal(stream)
    im = stream_normal(stream)
    z = cmplx(re, im, wp)
  end function next_complex_normal

  !> f^ = b^ - k (k.b^)/|k|^2 (paper Eq. 4): divergence-free forcing.
  subroutine project(self)
    type(ep_forcing_t), intent(inout) :: self
    integer :: m
    complex(wp) :: k_dot_b
    do m = 1, self%n_pairs
      associate (k => self%wavevector(:, m))
        k_dot_b = sum(k * self%b_hat(:, m))
        self%f_hat(:, m) = self%b_hat(:, m) - k * (k_dot_b / sum(k**2))
      end associate
    end do
  end subroutine project

  ! ------------------------------------------------------------------ evaluation

  !> fx, fy, fz (m/s^2 per unit scale) += scale * f at the u, v, w faces of the local slab's
  !> interior; arrays as the fluid allocates them, (0:nx+1, 0:ny+1, 0:nz_local+1). scale defaults to 1
  !> (e.g. scale = dt adds the forcing's velocity increment).
  subroutine forcing_add_to(self, fx, fy, fz, scale)
    type(ep_forcing_t), intent(in) :: self
    real(wp), intent(inout) :: fx(0:, 0:, 0:), fy(0:, 0:, 0:), fz(0:, 0:, 0:)
    real(wp), intent(in), optional :: scale
    real(wp) :: factor
    factor = 1.0_wp
    if (present(scale)) factor = scale
    call check_shape(self, fx); call check_shape(self, fy); call check_shape(self, fz)
    call evaluate_component(self, 1, factor, target=fx)
    call evaluate_component(self, 2, factor, target=fy)
    call evaluate_component(self, 3, factor, target=fz)
  end subroutine forcing_add_to

  !> field(1:nx, 1:ny, 1:nz_local) = f_component at that component's faces (1 = x, 2 = y, 3 = z).
  subroutine forcing_set_field(self, component, field)
    type(ep_forcing_t), intent(in) :: self
    integer, intent(in) :: component
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    call check_shape(self, field)
    call evaluate_component(self, component, 1.0_wp, target=field, overwrite=.true.)
  end subroutine forcing_set_field

  !> fx, fy, fz = f on the u, v, w faces of the local interior (halos untouched): the time loop's
  !> force arrays, written without a separate zeroing pass.
  subroutine forcing_set_fields(self, fx, fy, fz)
    type(ep_forcing_t), intent(in) :: self
    real(wp), intent(inout) :: fx(0:, 0:, 0:), fy(0:, 0:, 0:), fz(0:, 0:, 0:)
    call forcing_set_field(self, 1, fx)
    call forcing_set_field(self, 2, fy)
    call forcing_set_field(self, 3, fz)
  end subroutine forcing_set_fields

  !> Power input per unit mass <f.u> (m^2/s^3): the box average of f_x u + f_y v + f_z w, each
  !> product taken at the component's own faces. Collective (global sum over the ranks).
  function forcing_power_input(self, u, v, w) result(power)
    type(ep_forcing_t), intent(in) :: self
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp) :: power, dot(3)
    call check_shape(self, u); call check_shape(self, v); call check_shape(self, w)
    call evaluate_component(self, 1, 1.0_wp, velocity=u, dot=dot(1))
    call evaluate_component(self, 2, 1.0_wp, velocity=v, dot=dot(2))
    call evaluate_component(self, 3, 1.0_wp, velocity=w, dot=dot(3))
    power = global_sum(sum(dot)) / (real(self%nx, wp) * real(self%ny, wp) * real(self%nz, wp))
  end function forcing_power_input

  subroutine check_shape(self, field)
    type(ep_forcing_t), intent(in) :: self
    real(wp), intent(in) :: field(0:, 0:, 0:)
    if (.not. self%ready) call fatal('forcing: evaluation before forcing_init', collective=.false.)
    if (ubound(field, 1) < self%nx .or. ubound(field, 2) < self%ny .or. ubound(field, 3) < self%nz_local) &
        call fatal('forcing: field array smaller than the local slab (0:nx+1, 0:ny+1, 0:nz_local+1)', &
                   collective=.false.)
  end subroutine check_shape

  !> The separable direct sum for one component: with target, target += scale f (target = scale f
  !> with overwrite); with velocity and dot, dot = sum over the local faces of scale f * velocity.
  subroutine evaluate_component(self, component, scale, target, velocity, dot, overwrite)
    type(ep_forcing_t), intent(in) :: self
    integer, intent(in) :: component
    real(wp), intent(in) :: scale
    real(wp), intent(inout), optional :: target(0:, 0:, 0:)
    real(wp), intent(in), optional :: velocity(0:, 0:, 0:)
    real(wp), intent(out), optional :: dot
    logical, intent(in), optional :: overwrite
    real(wp) :: local_dot
    logical :: replace
    integer :: at_x, at_y, at_z, i, j, k, m, n1, n2
    ! Work arrays on the stack (their sizes follow the forced band, a few entries): nothing is
    ! allocated per call in the time loop.
    complex(wp) :: plane(0:self%mode_extent(1), -self%mode_extent(2):self%mode_extent(2))
    complex(wp) :: row_coefficient(0:self%mode_extent(1))
    real(wp) :: row(self%nx), row_re(0:self%mode_extent(1)), row_im(0:self%mode_extent(1))
    replace = .false.
    if (present(overwrite)) replace = overwrite
    associate (m1 => self%mode_extent(1), m2 => self%mode_extent(2), nx => self%nx)
      at_x = merge(at_face, at_centre, component == 1)
      at_y = merge(at_face, at_centre, component == 2)
      at_z = merge(at_face, at_centre, component == 3)
      local_dot = 0.0_wp
      do k = 1, self%nz_local
        ! plane(n1, n2) = sum over modes (n1, n2, n3) of 2 f^_c exp(i k3 z): the factor 2 is the
        ! Hermitian completion, f^ e^{ikx} + conj(f^ e^{ikx}) = 2 Re(f^ e^{ikx}).
        plane = (0.0_wp, 0.0_wp)
        do m = 1, self%n_pairs
          plane(self%modes(1, m), self%modes(2, m)) = plane(self%modes(1, m), self%modes(2, m)) + &
              2.0_wp * scale * self%f_hat(component, m) * self%ez(self%modes(3, m), k, at_z)
        end do
        do j = 1, self%ny
          row_coefficient = (0.0_wp, 0.0_wp)
          do n2 = -m2, m2
            do n1 = 0, m1
              row_coefficient(n1) = row_coefficient(n1) + plane(n1, n2) * self%ey(n2, j, at_y)
            end do
          end do
          row_re = real(row_coefficient, wp)
          row_im = aimag(row_coefficient)
          ! Re(c e^{i k1 x}) summed over the n1 columns: the n1 = 0 column is the constant Re(c_0)
          ! (e^0 = 1), then one vectorised multiply-add pass over the row per further column.
          row = row_re(0)
          do n1 = 1, m1
            do i = 1, nx
              row(i) = row(i) + (row_re(n1) * self%ex_re(i, n1, at_x) - row_im(n1) * self%ex_im(i, n1, at_x))
            end do
          end do
          if (present(target)) then
            if (replace) then
              target(1:nx, j, k) = row
            else
              target(1:nx, j, k) = target(1:nx, j, k) + row
            end if
          end if
          if (present(velocity)) local_dot = local_dot + dot_product(row, velocity(1:nx, j, k))
        end do
      end do
    end associate
    if (present(dot)) dot = local_dot
  end subroutine evaluate_component

  ! ------------------------------------------------------------------ checkpoint state

  !> Number of int64 words of the packed state.
  pure integer function forcing_state_size(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_state_size = state_header + stream_state_size + 6 * self%n_pairs
  end function forcing_state_size

  !> The full state as int64 words (bit-exact): format, pairs, update kind, steps, the stream,
  !> then Re and Im of b^ for every mode and component. The same on every rank.
  function forcing_pack_state(self) result(words)
    type(ep_forcing_t), intent(in) :: self
    integer(i8), allocatable :: words(:)
    integer :: m, c, at
    allocate(words(forcing_state_size(self)))
    words(1:state_header) = [state_format, int(self%n_pairs, i8), int(self%update_kind, i8), self%steps]
    words(state_header + 1:state_header + stream_state_size) = stream_pack(self%stream)
    at = state_header + stream_state_size
    do m = 1, self%n_pairs
      do c = 1, 3
        words(at + 1) = transfer(real(self%b_hat(c, m), wp), 0_i8)
        words(at + 2) = transfer(aimag(self%b_hat(c, m)), 0_i8)
        at = at + 2
      end do
    end do
  end function forcing_pack_state

  !> Restore a state packed by forcing_pack_state into a forcing set up from the same deck
  !> (same modes); the run then continues the same realisation bit for bit.
  subroutine forcing_unpack_state(self, words)
    type(ep_forcing_t), intent(inout) :: self
    integer(i8), intent(in) :: words(:)
    call check_packed_state(self, words, 'the checkpoint')
    self%steps = words(4)
    self%stream = stream_unpack(words(state_header + 1:state_header + stream_state_size))
    call unpack_coefficients(self, words)
  end subroutine forcing_unpack_state

  !> Only the OU coefficients b^ of a packed state (e.g. the forcing/state of the final field a
  !> fresh run starts from): f stays correlated with that field, so <f.u> starts at its stationary
  !> value instead of near zero. The deck's own random stream is kept (runs of a batch differ in
  !> their forcing from here on) and the step count restarts. source names the file for messages.
  subroutine forcing_restore_coefficients(self, words, source)
    type(ep_forcing_t), intent(inout) :: self
    integer(i8), intent(in) :: words(:)
    character(len=*), intent(in) :: source
    call check_packed_state(self, words, source)
    self%steps = 0_i8
    call unpack_coefficients(self, words)
  end subroutine forcing_restore_coefficients

  !> A packed state fits this forcing: known format, the same number of forced +-k pairs.
  subroutine check_packed_state(self, words, source)
    type(ep_forcing_t), intent(in) :: self
    integer(i8), intent(in) :: words(:)
    character(len=*), intent(in) :: source
    if (.not. self%ready) call fatal('forcing: restoring a state into a forcing that is not set up', &
                                     collective=.false.)
    if (size(words) < state_header) call fatal('forcing: the forcing state of '//source//' is truncated')
    if (words(1) /= state_format) call fatal('forcing: the forcing state of '//source//' has an unknown format')
    if (words(2) /= int(self%n_pairs, i8) .or. size(words) /= forcing_state_size(self)) call fatal( &
        'forcing: '//source//' has '//int_text(int(words(2)))//' forced +-k pairs, the deck gives '// &
        int_text(self%n_pairs)//' (&forcing kappa_f_ratio or the &grid box differ from the run that wrote it)')
    if (words(3) /= int(self%update_kind, i8)) call log_line('forcing: note: the update form differs from '// &
        'that of '//source//'; the OU state continues with the deck''s form')
  end subroutine check_packed_state

  !> b^ from the words after the header and the stream (forcing_pack_state's order), then f^.
  subroutine unpack_coefficients(self, words)
    type(ep_forcing_t), intent(inout) :: self
    integer(i8), intent(in) :: words(:)
    integer :: m, c, at
    at = state_header + stream_state_size
    do m = 1, self%n_pairs
      do c = 1, 3
        self%b_hat(c, m) = cmplx(transfer(words(at + 1), 0.0_wp), transfer(words(at + 2), 0.0_wp), wp)
        at = at + 2
      end do
    end do
    call project(self)
  end subroutine unpack_coefficients

  ! ------------------------------------------------------------------ accessors

  pure integer function forcing_pair_count(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_pair_count = self%n_pairs
  end function forcing_pair_count

  !> (3, pairs) integer vectors n of the evolved half set; k = 2 pi n / L.
  pure function forcing_mode_integers(self) result(modes)
    type(ep_forcing_t), intent(in) :: self
    integer :: modes(3, self%n_pairs)
    modes = self%modes
  end function forcing_mode_integers

  pure function forcing_wavevectors(self) result(k)
    type(ep_forcing_t), intent(in) :: self
    real(wp) :: k(3, self%n_pairs)
    k = self%wavevector
  end function forcing_wavevectors

  !> OU coefficients b^ (3, pairs), m/s^2.
  pure function forcing_coefficients(self) result(b)
    type(ep_forcing_t), intent(in) :: self
    complex(wp) :: b(3, self%n_pairs)
    b = self%b_hat
  end function forcing_coefficients

  !> Projected coefficients f^ (3, pairs), m/s^2; f^(-k) = conj(f^(k)).
  pure function forcing_projected(self) result(f)
    type(ep_forcing_t), intent(in) :: self
    complex(wp) :: f(3, self%n_pairs)
    f = self%f_hat
  end function forcing_projected

  pure real(wp) function forcing_sigma(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_sigma = self%sigma
  end function forcing_sigma

  pure real(wp) function forcing_epsilon_star(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_epsilon_star = self%epsilon_star
  end function forcing_epsilon_star

  pure real(wp) function forcing_time_scale(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_time_scale = self%time_scale
  end function forcing_time_scale

  pure real(wp) function forcing_kappa0(self)
    type(ep_forcing_t), intent(in) :: self
    forcing_kappa0 = self%kappa0
  end function forcing_kappa0

end module eswaran_pope_forcing
