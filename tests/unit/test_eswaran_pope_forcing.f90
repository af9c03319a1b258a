! checks: 31
!> Unit tests of eswaran_pope_forcing: the forced wavevector set, the Fourier content of the
!> evaluated field (FFTW, serial), divergence-free coefficients (Eq. 4), Hermitian completion (real
!> field), independence of the slab decomposition, the power input <f.u> (Parseval), the E&P
!> estimate and its inverse, and bit-for-bit continuation from a packed state.
!> References: docs/physics.md section 3; paper section 2.1, Eqs. 2-6.
program test_eswaran_pope_forcing
  use, intrinsic :: iso_c_binding
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use config_forcing, only: forcing_config_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init, forcing_advance, forcing_set_field, forcing_add_to, &
      forcing_power_input, forcing_pack_state, forcing_unpack_state, forcing_pair_count, forcing_mode_integers, &
      forcing_wavevectors, forcing_projected, forcing_coefficients, forcing_epsilon_star, forcing_sigma, &
      forcing_kappa0, ep_power_estimate, epsilon_star_for_dissipation, forcing_restore_coefficients
  use parallel_env, only: parallel_start
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  include 'fftw3.f03'

  type(forcing_config_t) :: cfg
  type(ep_forcing_t) :: forcing

  call parallel_start()
  call test_start('eswaran_pope_forcing')

  cfg%time_scale = 0.01_wp
  cfg%sigma = 0.37_wp

  call test_mode_set()
  ! A cubic box and a box with unequal sides and cell counts (k = 2 pi n_d / L_d per axis).
  call test_fourier_content([16, 16, 16], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], 'cubic')
  call test_fourier_content([16, 12, 10], [1.0e-3_wp, 0.9e-3_wp, 1.2e-3_wp], 'uneven')
  call test_slab_independence()
  call test_power_input()
  call test_strength_inputs()
  call test_pack_unpack()
  call test_restore_coefficients()

  call test_finish()

contains

  !> kappa_F = 2.3 kappa0 in a cubic box forces exactly the 56 vectors with 0 < |n|^2 <= 5, i.e. 28
  !> +-k pairs (docs/physics.md section 3: 6 + 12 + 8 + 6 + 24 vectors on the shells |n|^2 = 1..5).
  subroutine test_mode_set()
    integer, allocatable :: modes(:,:)
    integer :: m, other, squared
    logical :: no_pair_twice, all_in_range
    call forcing_init(forcing, cfg, 11, [16, 16, 16], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], 16, 0)
    call check_equal(forcing_pair_count(forcing), 28, 'pairs_for_kappa_f_2.3')
    modes = forcing_mode_integers(forcing)
    all_in_range = .true.
    no_pair_twice = .true.
    do m = 1, size(modes, 2)
      squared = sum(modes(:, m)**2)
      all_in_range = all_in_range .and. squared >= 1 .and. squared <= 5
      do other = 1, size(modes, 2)
        if (all(modes(:, other) == -modes(:, m))) no_pair_twice = .false.
      end do
    end do
    call check(all_in_range, 'modes_have_0<|n|^2<=5')
    call check(no_pair_twice, 'half_set_holds_one_of_each_pm_k_pair')
    call check_close(forcing_kappa0(forcing), two_pi / 1.0e-3_wp, 1.0e-14_wp, 'kappa0_is_2pi_over_L')
    ! A cut-off typed as sqrt(5) to 10 digits still includes the |n|^2 = 5 shell (56 vectors);
    ! just below it the shell drops out: 56 - 24 = 32 vectors, 16 pairs.
    cfg%kappa_f_ratio = 2.2360679775_wp
    call forcing_init(forcing, cfg, 11, [16, 16, 16], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], 16, 0)
    call check_equal(forcing_pair_count(forcing), 28, 'cutoff_sqrt5_includes_shell_5')
    cfg%kappa_f_ratio = 2.2_wp
    call forcing_init(forcing, cfg, 11, [16, 16, 16], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], 16, 0)
    call check_equal(forcing_pair_count(forcing), 16, 'cutoff_2.2_forces_shells_1_to_4')
    cfg%kappa_f_ratio = 2.3_wp
  end subroutine test_mode_set

  !> Sample each component at its own MAC faces, FFT it, and compare with the coefficients:
  !> content only on the forced +-k (relative 1e-12), recovered f^ equal to the module's (1e-12),
  !> k.f^ = 0 (1e-12 relative to |k| max|f^|), and the direct complex synthesis over all +-k is real
  !> and equal to the evaluated field (1e-12): the Hermitian completion is right.
  subroutine test_fourier_content(cells, lengths, label)
    integer, intent(in) :: cells(3)
    real(wp), intent(in) :: lengths(3)
    character(len=*), intent(in) :: label
    real(wp), allocatable :: field(:,:,:), k(:,:)
    complex(c_double_complex), allocatable :: samples(:,:,:), spectrum(:,:,:)
    complex(wp), allocatable :: f_hat(:,:), recovered(:,:), synthesis
    integer, allocatable :: modes(:,:)
    logical, allocatable :: forced(:,:,:)
    type(c_ptr) :: plan
    integer :: c, m, i, j, l, sign_k, idx(3)
    real(wp) :: shift(3), outside, inside, coefficient_error, divergence, f_scale, imaginary, mismatch, x(3)
    complex(wp) :: phase, value

    call forcing_init(forcing, cfg, 5, cells, lengths, cells(3), 0)
    do i = 1, 7
      call forcing_advance(forcing, 1.0e-3_wp)
    end do
    f_hat = forcing_projected(forcing)
    modes = forcing_mode_integers(forcing)
    k = forcing_wavevectors(forcing)
    f_scale = maxval(abs(f_hat))
    allocate(field(0:cells(1) + 1, 0:cells(2) + 1, 0:cells(3) + 1), forced(cells(1), cells(2), cells(3)))
    allocate(samples(cells(1), cells(2), cells(3)), spectrum(cells(1), cells(2), cells(3)))
    allocate(recovered(3, size(modes, 2)))
    forced = .false.
    do m = 1, size(modes, 2)
      do sign_k = -1, 1, 2
        idx = modulo(sign_k * modes(:, m), cells) + 1
        forced(idx(1), idx(2), idx(3)) = .true.
      end do
    end do
    plan = fftw_plan_dft_3d(cells(3), cells(2), cells(1), samples, spectrum, FFTW_FORWARD, FFTW_ESTIMATE)
    outside = 0.0_wp; inside = 0.0_wp; imaginary = 0.0_wp; mismatch = 0.0_wp
    do c = 1, 3
      call forcing_set_field(forcing, c, field)
      samples = cmplx(field(1:cells(1), 1:cells(2), 1:cells(3)), 0.0_wp, c_double_complex)
      call fftw_execute_dft(plan, samples, spectrum)
      spectrum = spectrum / product(real(cells, wp))
      outside = max(outside, maxval(abs(spectrum), mask=.not. forced))
      inside = max(inside, maxval(abs(spectrum), mask=forced))
      ! Sample (i,j,l) of component c sits at x_d = (index_d - shift_d) dx_d, shift 0 at a face, 1/2 at a
      ! centre: the DFT over index - 1 carries the phase exp(i k.(1 - shift) dx) per mode.
      shift = 0.5_wp
      shift(c) = 0.0_wp
      do m = 1, size(modes, 2)
        idx = modulo(modes(:, m), cells) + 1
        phase = exp(cmplx(0.0_wp, -two_pi * sum(real(modes(:, m), wp) * (1.0_wp - shift) / real(cells, wp)), wp))
        recovered(c, m) = spectrum(idx(1), idx(2), idx(3)) * phase
      end do
      ! Direct synthesis over the full set of +-k (f^(-k) = conj f^(k)) at a few sample points.
      do l = 1, cells(3), 3
        do j = 1, cells(2), 2
          do i = 1, cells(1), 3
            x = (real([i, j, l], wp) - shift) * lengths / real(cells, wp)
            synthesis = (0.0_wp, 0.0_wp)
            do m = 1, size(modes, 2)
              value = f_hat(c, m) * exp(cmplx(0.0_wp, sum(k(:, m) * x), wp))
              synthesis = synthesis + value + conjg(f_hat(c, m)) * exp(cmplx(0.0_wp, -sum(k(:, m) * x), wp))
            end do
            imaginary = max(imaginary, abs(aimag(synthesis)))
            mismatch = max(mismatch, abs(real(synthesis, wp) - field(i, j, l)))
          end do
        end do
      end do
    end do
    call fftw_destroy_plan(plan)
    coefficient_error = maxval(abs(recovered - f_hat)) / f_scale
    divergence = 0.0_wp
    do m = 1, size(modes, 2)
      divergence = max(divergence, abs(sum(k(:, m) * recovered(:, m))) / (norm2(k(:, m)) * f_scale))
    end do
    ! Reference: content only on the forced wavevectors (docs/physics.md section 3), Eq. 4.
    call check_below(outside / inside, 1.0e-12_wp, label//'_spectrum_only_on_forced_wavevectors')
    call check_below(coefficient_error, 1.0e-12_wp, label//'_fft_recovers_f_hat')
    call check_below(divergence, 1.0e-12_wp, label//'_k_dot_f_hat_zero')
    call check_below(imaginary / f_scale, 1.0e-12_wp, label//'_hermitian_synthesis_is_real')
    call check_below(mismatch / f_scale, 1.0e-12_wp, label//'_separable_sum_equals_direct_synthesis')
  end subroutine test_fourier_content

  !> The forcing on two z slabs (as two ranks would hold them) equals the one-slab field bit for bit.
  subroutine test_slab_independence()
    type(ep_forcing_t) :: lower, upper
    real(wp), allocatable :: whole(:,:,:), part(:,:,:)
    integer, parameter :: n(3) = [12, 10, 8]
    real(wp), parameter :: lengths(3) = [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp]
    logical :: same
    integer :: c, step
    call forcing_init(forcing, cfg, 3, n, lengths, n(3), 0)
    call forcing_init(lower, cfg, 3, n, lengths, n(3) / 2, 0)
    call forcing_init(upper, cfg, 3, n, lengths, n(3) / 2, n(3) / 2)
    do step = 1, 5
      call forcing_advance(forcing, 2.0e-3_wp)
      call forcing_advance(lower, 2.0e-3_wp)
      call forcing_advance(upper, 2.0e-3_wp)
    end do
    allocate(whole(0:n(1) + 1, 0:n(2) + 1, 0:n(3) + 1), part(0:n(1) + 1, 0:n(2) + 1, 0:n(3) / 2 + 1))
    same = .true.
    do c = 1, 3
      call forcing_set_field(forcing, c, whole)
      call forcing_set_field(lower, c, part)
      same = same .and. all(part(1:n(1), 1:n(2), 1:n(3) / 2) == whole(1:n(1), 1:n(2), 1:n(3) / 2))
      call forcing_set_field(upper, c, part)
      same = same .and. all(part(1:n(1), 1:n(2), 1:n(3) / 2) == whole(1:n(1), 1:n(2), n(3) / 2 + 1:n(3)))
    end do
    call check(same, 'two_slabs_equal_one_slab_bit_for_bit')
  end subroutine test_slab_independence

  !> With u = f (each component on its faces), <f.u> = <|f|^2> = sum over all +-k |f^|^2
  !> = 2 sum_half |f^|^2 (Parseval; exact on the grid because every mode is below Nyquist).
  !> add_to with scale 2 on zero arrays gives twice the field.
  subroutine test_power_input()
    real(wp), allocatable :: u(:,:,:), v(:,:,:), w(:,:,:), fx(:,:,:), fy(:,:,:), fz(:,:,:)
    integer, parameter :: n(3) = [16, 12, 10]
    real(wp) :: expected
    call forcing_init(forcing, cfg, 9, n, [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], n(3), 0)
    call forcing_advance(forcing, 1.0e-3_wp)
    allocate(u(0:n(1) + 1, 0:n(2) + 1, 0:n(3) + 1), source=0.0_wp)
    allocate(v, w, fx, fy, fz, mold=u)
    v = 0.0_wp; w = 0.0_wp   ! halos too: the comparison below spans the whole arrays
    call forcing_set_field(forcing, 1, u)
    call forcing_set_field(forcing, 2, v)
    call forcing_set_field(forcing, 3, w)
    expected = 2.0_wp * sum(abs(forcing_projected(forcing))**2)
    call check_close(forcing_power_input(forcing, u, v, w), expected, 1.0e-12_wp, 'power_input_parseval')
    fx = 0.0_wp; fy = 0.0_wp; fz = 0.0_wp
    call forcing_add_to(forcing, fx, fy, fz, scale=2.0_wp)
    call check_below(maxval(abs(fx - 2.0_wp * u)) + maxval(abs(fy - 2.0_wp * v)) + maxval(abs(fz - 2.0_wp * w)), &
                     1.0e-13_wp * maxval(abs(u)), 'add_to_scale_2_adds_twice_the_field')
  end subroutine test_power_input

  !> The three ways to set the strength agree (epsilon* = sigma^2 T_L, paper after Eq. 3), and the
  !> target-dissipation route inverts the E&P estimate (docs/physics.md section 3).
  subroutine test_strength_inputs()
    type(forcing_config_t) :: other
    real(wp), parameter :: lengths(3) = [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp]
    real(wp) :: epsilon_star, kappa0, target
    call forcing_init(forcing, cfg, 1, [8, 8, 8], lengths, 8, 0)
    call check_close(forcing_epsilon_star(forcing), cfg%sigma**2 * cfg%time_scale, 1.0e-15_wp, 'epsilon_star_from_sigma')
    other%time_scale = cfg%time_scale
    other%epsilon_star = 2.5e-3_wp
    call forcing_init(forcing, other, 1, [8, 8, 8], lengths, 8, 0)
    call check_close(forcing_sigma(forcing), sqrt(2.5e-3_wp / cfg%time_scale), 1.0e-15_wp, 'sigma_from_epsilon_star')
    kappa0 = two_pi / 1.0e-3_wp
    target = 8.0e-3_wp
    epsilon_star = epsilon_star_for_dissipation(target, 0.01_wp, kappa0, 56)
    call check_close(ep_power_estimate(epsilon_star, 0.01_wp, kappa0, 56), target, 1.0e-13_wp, 'ep_estimate_inverse')
    other%epsilon_star = -huge(1.0_wp)
    other%target_dissipation = target
    call forcing_init(forcing, other, 1, [8, 8, 8], lengths, 8, 0)
    call check_close(forcing_epsilon_star(forcing), epsilon_star, 1.0e-15_wp, 'epsilon_star_from_target_dissipation')
    ! White-noise limit T_L -> 0: the estimate tends to 4 N_F epsilon* (E&P 1988).
    call check_close(ep_power_estimate(1.0e-4_wp, 1.0e-12_wp, kappa0, 56), 4.0_wp * 56 * 1.0e-4_wp, 1.0e-6_wp, &
                     'ep_estimate_white_noise_limit')
  end subroutine test_strength_inputs

  !> Pack after some steps, continue; a forcing restored from the packed words into a fresh set-up with
  !> another seed continues with the same coefficients and the same field, bit for bit.
  subroutine test_pack_unpack()
    type(ep_forcing_t) :: restored
    integer(i8), allocatable :: words(:)
    real(wp), allocatable :: a(:,:,:), b(:,:,:)
    integer, parameter :: n(3) = [8, 8, 8]
    real(wp), parameter :: lengths(3) = [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp]
    logical :: same
    integer :: step, c
    do c = 1, 2
      if (c == 2) cfg%update = 'euler_maruyama'
      call forcing_init(forcing, cfg, 21, n, lengths, n(3), 0)
      do step = 1, 13
        call forcing_advance(forcing, 1.0e-4_wp)
      end do
      words = forcing_pack_state(forcing)
      call forcing_init(restored, cfg, 99, n, lengths, n(3), 0)
      call forcing_unpack_state(restored, words)
      same = .true.
      do step = 1, 17
        call forcing_advance(forcing, 1.0e-4_wp)
        call forcing_advance(restored, 1.0e-4_wp)
        same = same .and. all(forcing_coefficients(forcing) == forcing_coefficients(restored))
      end do
      allocate(a(0:n(1) + 1, 0:n(2) + 1, 0:n(3) + 1), b(0:n(1) + 1, 0:n(2) + 1, 0:n(3) + 1))
      call forcing_set_field(forcing, 3, a)
      call forcing_set_field(restored, 3, b)
      same = same .and. all(a(1:n(1), 1:n(2), 1:n(3)) == b(1:n(1), 1:n(2), 1:n(3)))
      deallocate(a, b)
      call check(same, 'pack_unpack_continues_bit_for_bit_'//trim(cfg%update))
    end do
    cfg%update = 'exact'
  end subroutine test_pack_unpack

  !> Start from a forced field (&forcing initial_state = 'field'): only b^ of a packed state are
  !> taken; the stream stays the deck's own (seed 99: the same words and draws as an untouched set-up
  !> with seed 99) and the step count restarts. Packed words (int64) compared, so bit for bit.
  subroutine test_restore_coefficients()
    type(ep_forcing_t) :: restored, own_seed
    integer(i8), allocatable :: written(:), after(:), reference(:)
    integer, parameter :: n(3) = [8, 8, 8]
    real(wp), parameter :: lengths(3) = [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp]
    integer :: step, first_b
    call forcing_init(forcing, cfg, 21, n, lengths, n(3), 0)
    do step = 1, 13
      call forcing_advance(forcing, 1.0e-4_wp)
    end do
    written = forcing_pack_state(forcing)
    call forcing_init(restored, cfg, 99, n, lengths, n(3), 0)
    call forcing_init(own_seed, cfg, 99, n, lengths, n(3), 0)
    call forcing_restore_coefficients(restored, written, 'test words')
    after = forcing_pack_state(restored)
    reference = forcing_pack_state(own_seed)
    first_b = size(written) - 6 * forcing_pair_count(forcing) + 1
    call check(all(after(first_b:) == written(first_b:)), 'restore_coefficients_takes_b_hat')
    call check(all(after(5:first_b - 1) == reference(5:first_b - 1)), 'restore_coefficients_keeps_own_stream')
    call check_equal(int(after(4)), 0, 'restore_coefficients_restarts_step_count')
    call check(all(forcing_projected(restored) == forcing_projected(forcing)), 'restore_coefficients_projects_f_hat')
    call forcing_advance(restored, 1.0e-4_wp)
    call forcing_advance(own_seed, 1.0e-4_wp)
    after = forcing_pack_state(restored)
    reference = forcing_pack_state(own_seed)
    call check(all(after(5:first_b - 1) == reference(5:first_b - 1)), 'restore_coefficients_draws_from_own_stream')
  end subroutine test_restore_coefficients
end program test_eswaran_pope_forcing
