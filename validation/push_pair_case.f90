!> The free approach of two equal bodies pushed together by constant equal and opposite forces +-F
!> along their line of centres in fluid at rest (docs/studies/validation.md, "Free approach under a
!> constant force"), no DLVO, no collisions, with the sub-grid lubrication of the particle system.
!>
!> Reference for spheres: the quasi-steady approach under the exact two-sphere resistance along the
!> line of centres, F = 6 pi mu a lambda(h/a) U for each sphere moving at U, so
!>   dh/dt = -2 F / (6 pi mu a lambda(h/a)),
!> lambda from Brenner's (1961) bispherical series (squeeze_case, brenner_squeeze_coefficient) down
!> to h/a = 1e-2 and the near-contact form below it,
!>   lambda = 1/(2 eps) + (9/20) ln(1/eps) + (3/56) eps ln(1/eps) + 1.3458,   eps = h/a
!> (Jeffrey & Onishi 1984, J. Fluid Mech. 139, 261; Kim & Karrila 1991, ch. 11; the two agree to
!> 3e-5 at 1e-2), integrated in ln h (quasi_steady_times).
!> For needles tip to tip and disks face to face (symmetry axes on the line of centres) the
!> reference is the curvature-scaled near-contact asymptote: each body's isolated axial drag
!> zeta plus the leading squeeze resistance 6 pi mu R_eff^2 / h (R_eff^2 = 2 / (tr K sqrt(det K)),
!> R_eff = rho / 2 for two tips or faces of radius of curvature rho), i.e.
!>   dh/dt = -2 F / (zeta + 2 * 6 pi mu R_eff^2 / h),
!> t(h1 -> h2) = zeta (h1 - h2) / (2 F) + (6 pi mu R_eff^2 / F) ln(h1 / h2).
!>
!> The 'stokes' rung (run_stokes_push): each body feels the quasi-steady drag of its isolated
!> resistance tensors (module stokes_hydrodynamics, the 'stokes' scene's provider) and the push;
!> the particle system adds the lubrication impulse at the hand-over of the 'stokes' scene (one
!> radius; config_collision, default_lubrication_handover). The resolved rung runs through
!> squeeze_case's run_free_squeeze (bench_push_pair).
module push_pair_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero
  use lubrication, only: lubrication_model_t
  use stokes_hydrodynamics, only: stokes_hydrodynamics_t, stokes_hydrodynamics_create
  use stokes_resistance, only: spheroid_resistance_coefficients
  use squeeze_case, only: brenner_squeeze_coefficient
  implicit none
  private
  public :: push_case_t, push_history_t, run_stokes_push, two_sphere_lambda, quasi_steady_times, &
            history_gap_error, history_time_error, history_time_at, tip_asymptote_time

  type :: push_case_t
    character(len=8) :: shape = 'sphere'         !< 'sphere', 'needle' (tip to tip) or 'disk' (face to face)
    real(wp) :: aspect_ratio = 5.0_wp            !< needle a/b, disk b/a
    real(wp) :: radius = 50.0e-6_wp              !< m, volume-equivalent r
    real(wp) :: density = 2710.0_wp              !< kg/m^3 (calcite)
    real(wp) :: viscosity = 1.0e-3_wp            !< Pa s (water)
    real(wp) :: stokes_number = 1.0e-3_wp        !< tau U_p / r: tau = m / (6 pi mu r), U_p = F / (6 pi mu r)
    real(wp) :: start_gap = 2.0_wp               !< h / r at the start (both bodies at rest)
    real(wp) :: stop_gap = 5.0e-9_wp             !< m, the run ends below this gap
    real(wp) :: handover = 1.0_wp                !< h_out / r
    real(wp) :: roughness = 1.0e-9_wp            !< m, h_in
    real(wp) :: step_fraction = 0.1_wp           !< dt / tau
  end type push_case_t

  !> The recorded approach, one row per particle step.
  type :: push_history_t
    real(wp), allocatable :: time(:)             !< s
    real(wp), allocatable :: gap(:)              !< m
    real(wp) :: push = 0                         !< N, F
    real(wp) :: axial_drag = 0                   !< N s/m, zeta of one body along the line of centres
    real(wp) :: reduced_radius = 0               !< m, R_eff of the two surfaces at the closest points
    logical :: reached = .false.                 !< the gap fell below stop_gap
  end type push_history_t

contains

  !> lambda(eps) of the module header: the exact resistance of two equal spheres approaching along
  !> their line of centres, in units of 6 pi mu a U.
  pure real(wp) function two_sphere_lambda(eps)
    real(wp), intent(in) :: eps
    if (eps >= 1.0e-2_wp) then
      two_sphere_lambda = brenner_squeeze_coefficient(eps)
    else
      two_sphere_lambda = 0.5_wp / eps + 0.45_wp * log(1.0_wp / eps) + 3.0_wp / 56.0_wp * eps * log(1.0_wp / eps) &
                          + 1.3458_wp
    end if
  end function two_sphere_lambda

  !> Times (s) at which the quasi-steady approach of two spheres of radius a under the push F
  !> reaches each of gaps(:) (m, decreasing, below start_gap): t = int_h^h0 6 pi mu a lambda / (2 F)
  !> dh, by the trapezoidal rule in ln h with 2000 points per decade.
  pure function quasi_steady_times(push, radius, viscosity, start_gap, gaps) result(times)
    real(wp), intent(in) :: push, radius, viscosity, start_gap, gaps(:)
    real(wp) :: times(size(gaps))
    real(wp) :: t, u, du, h_prev, h, f_prev, f
    integer :: k, n, i
    t = 0
    h_prev = start_gap
    f_prev = rate(h_prev)
    do k = 1, size(gaps)
      n = max(1, ceiling(2000.0_wp * log10(h_prev / gaps(k))))
      du = log(h_prev / gaps(k)) / n
      do i = 1, n
        u = log(h_prev) - du
        h = exp(u)
        f = rate(h)
        t = t + 0.5_wp * du * (f_prev + f)
        h_prev = h
        f_prev = f
      end do
      h_prev = gaps(k)
      times(k) = t
    end do

  contains

    !> dt / d(ln h) = h 6 pi mu a lambda / (2 F)
    pure real(wp) function rate(gap)
      real(wp), intent(in) :: gap
      rate = gap * 6.0_wp * pi * viscosity * radius * two_sphere_lambda(gap / radius) / (2.0_wp * push)
    end function rate
  end function quasi_steady_times

  !> The curvature-scaled asymptote of the module header: time (s) from gap h1 to h2 (m).
  pure real(wp) function tip_asymptote_time(history, viscosity, h1, h2)
    type(push_history_t), intent(in) :: history
    real(wp), intent(in) :: viscosity, h1, h2
    tip_asymptote_time = history%axial_drag * (h1 - h2) / (2.0_wp * history%push) &
                         + 6.0_wp * pi * viscosity * history%reduced_radius**2 / history%push * log(h1 / h2)
  end function tip_asymptote_time

  !> The time (s) at which a history's gap first falls to gap (m), linear between two rows; -1 if never.
  pure real(wp) function history_time_at(time, gaps, gap)
    real(wp), intent(in) :: time(:), gaps(:), gap
    integer :: s
    history_time_at = -1.0_wp
    do s = 2, size(gaps)
      if (gaps(s) <= gap) then
        history_time_at = time(s - 1) + (gap - gaps(s - 1)) / (gaps(s) - gaps(s - 1)) * (time(s) - time(s - 1))
        return
      end if
    end do
  end function history_time_at

  !> The largest |t(h) / t_ref(h) - 1| over the reference points (ref_time(k), ref_gap(k)) the
  !> history reaches (history_time_at).
  pure real(wp) function history_time_error(time, gaps, ref_time, ref_gap) result(worst)
    real(wp), intent(in) :: time(:), gaps(:), ref_time(:), ref_gap(:)
    integer :: k
    real(wp) :: t
    worst = 0
    do k = 1, size(ref_time)
      t = history_time_at(time, gaps, ref_gap(k))
      if (t > 0.0_wp) worst = max(worst, abs(t / ref_time(k) - 1.0_wp))
    end do
  end function history_time_error

  !> The largest |h(t) / h_ref(t) - 1| over the reference points (ref_time(k), ref_gap(k)) that lie
  !> within the history's time span; h(t) linear between two rows.
  pure real(wp) function history_gap_error(time, gaps, ref_time, ref_gap) result(worst)
    real(wp), intent(in) :: time(:), gaps(:), ref_time(:), ref_gap(:)
    integer :: k, s
    real(wp) :: h
    worst = 0
    s = 2
    do k = 1, size(ref_time)
      if (ref_time(k) < time(1) .or. ref_time(k) > time(size(time))) cycle
      do while (s < size(time))
        if (time(s) >= ref_time(k)) exit
        s = s + 1
      end do
      h = gaps(s - 1) + (ref_time(k) - time(s - 1)) / (time(s) - time(s - 1)) * (gaps(s) - gaps(s - 1))
      worst = max(worst, abs(h / ref_gap(k) - 1.0_wp))
    end do
  end function history_gap_error

  !> The 'stokes' rung (module header): two bodies at rest start_gap r apart on the x axis,
  !> symmetry axes along x, pushed together until the gap is below stop_gap.
  subroutine run_stokes_push(case, history)
    type(push_case_t), intent(in) :: case
    type(push_history_t), intent(out) :: history
    type(spheroid_t) :: shapes(2)
    type(rigid_body_t) :: bodies(2)
    type(particle_models_t) :: models
    type(particle_system_t) :: system
    type(particle_loads_t) :: loads
    type(stokes_hydrodynamics_t) :: provider
    real(wp), allocatable :: rows(:, :), grown(:, :)
    real(wp) :: drag, tau, dt, half_length, t, coefficients(4)
    integer :: n, steps
    do n = 1, 2
      if (case%shape == 'sphere') then
        shapes(n) = make_spheroid('sphere', case%radius, case%density)
      else
        shapes(n) = make_spheroid(trim(case%shape), case%radius, case%density, case%aspect_ratio)
      end if
    end do
    half_length = shapes(1)%a + 0.5_wp * case%start_gap * case%radius   ! symmetry-axis semi-axis + h/2
    do n = 1, 2
      call rigid_body_of_spheroid(bodies(n), shapes(n), [(2 * n - 3) * half_length, 0.0_wp, 0.0_wp], &
                                  [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    end do
    models%integrator = integrator_euler
    models%lubrication = .true.
    models%lubrication_model = lubrication_model_t(dynamic_viscosity=case%viscosity, &
                                                   outer_gap=case%handover * case%radius, roughness=case%roughness)
    call particle_system_create(system, shapes, bodies, models)
    drag = 6.0_wp * pi * case%viscosity * case%radius
    tau = shapes(1)%mass / drag
    dt = case%step_fraction * tau
    call particle_system_interact(system, dt)
    call stokes_hydrodynamics_create(provider, system, case%viscosity)
    coefficients = spheroid_resistance_coefficients(shapes(1)%a, shapes(1)%b)
    history%axial_drag = drag * coefficients(1)
    history%push = drag * case%stokes_number * case%radius / tau   ! U_p = St r / tau
    loads = particle_loads_zero(2)
    allocate(rows(2, 4096))
    steps = 1
    rows(:, 1) = [0.0_wp, system%pairs(1)%contact%gap]
    t = 0
    do while (system%pairs(1)%contact%gap >= case%stop_gap .and. steps < 50000000)
      call provider%loads(system, 0.0_wp, loads)
      loads%force(1, 1) = loads%force(1, 1) + history%push
      loads%force(1, 2) = loads%force(1, 2) - history%push
      call particle_system_step(system, dt, loads)
      t = t + dt
      steps = steps + 1
      if (steps > size(rows, 2)) then
        allocate(grown(2, 2 * size(rows, 2)))
        grown(:, 1:size(rows, 2)) = rows
        call move_alloc(grown, rows)
      end if
      rows(:, steps) = [t, system%pairs(1)%contact%gap]
      if (system%pairs(1)%lubrication%active) history%reduced_radius = system%pairs(1)%lubrication%geometry%reduced_radius
    end do
    history%reached = system%pairs(1)%contact%gap < case%stop_gap
    history%time = rows(1, 1:steps)
    history%gap = rows(2, 1:steps)
  end subroutine run_stokes_push
end module push_pair_case
