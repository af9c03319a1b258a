! checks: 14
!> The imposition of immersed_imposition on fields it must leave unchanged (docs/studies/validation.md,
!> rung 3: the mirror is exact for linear fields). A rigid-body field u = U + Omega x (x - X) over
!> the whole box near a translating, rotating needle and a sphere (random orientation and sub-cell
!> position, away from the periodic wrap so the field is linear over every stencil): trilinear
!> interpolation reproduces a linear field, so u_M - u_B = d_M (grad u) n and u_G - u_B =
!> -d_G (grad u) n, and every ghost row, pure mirror (implicit) or image point at 1.5 cells
!> (explicit), already holds. The imposition must change no value by more than 1e-12 of the
!> velocity scale, and the momentum it adds must vanish to the same relative level.
program test_immersed_boundary
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t, node_position
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use immersed_loads, only: ibm_begin_step
  use test_framework, only: test_start, test_finish, check_below, check
  implicit none
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_boundary_t) :: ibm
  type(immersed_body_t) :: bodies(1)
  type(imposition_report_t) :: report
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :), u0(:, :, :), v0(:, :, :), w0(:, :, :)
  real(wp) :: velocity(3, 1), angular_velocity(3, 1), dx, change, momentum_scale
  integer :: trial, body_kind
  character(len=8), parameter :: couplings(2) = [character(len=8) :: 'implicit', 'explicit']
  character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'sphere']

  call parallel_start()
  call test_start('immersed_boundary')
  call stream_seed(stream, 31_i8, stream_id=4)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  dx = grid%dx
  call allocate_field(grid, u); call allocate_field(grid, v); call allocate_field(grid, w)
  do trial = 1, 2
    do body_kind = 1, 2
      if (shapes(body_kind) == 'needle') then
        bodies(1)%shape = make_spheroid('needle', 5.0_wp * dx, 1000.0_wp, 3.0_wp)
      else
        bodies(1)%shape = make_spheroid('sphere', 6.0_wp * dx, 1000.0_wp)
      end if
      bodies(1)%centre = (16.0_wp + [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]) * dx
      bodies(1)%orientation = random_orientation(stream)
      velocity(:, 1) = [1.0e-3_wp, -2.0e-3_wp, 0.5e-3_wp]
      angular_velocity(:, 1) = [3.0_wp, -1.0_wp, 2.0_wp]
      ibm = immersed_boundary_t()
      ibm%settings%coupling = couplings(trial)
      call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, classify=.true.)
      call fill_rigid(1, u); call fill_rigid(2, v); call fill_rigid(3, w)
      call ibm_begin_step(ibm, grid, u, v, w)
      u0 = u; v0 = v; w0 = w
      call ibm_impose(ibm, grid, u, v, w, report)
      ! Interior nodes only: the imposition ends with the periodic halo exchange, and the linear field
      ! is not periodic.
      change = max(maxval(abs(u(1:32, 1:32, 1:32) - u0(1:32, 1:32, 1:32))), &
                   maxval(abs(v(1:32, 1:32, 1:32) - v0(1:32, 1:32, 1:32))), &
                   maxval(abs(w(1:32, 1:32, 1:32) - w0(1:32, 1:32, 1:32)))) / report%velocity_scale
      call check_below(change, 1.0e-12_wp, trim(couplings(trial))//'_'//trim(shapes(body_kind))// &
                       '_linear_field_unchanged')
      momentum_scale = 1000.0_wp * grid%cell_volume * report%velocity_scale * &
                       sum(ibm%geometry%component(:)%n_ghost + ibm%geometry%component(:)%n_interior)
      call check_below(maxval(abs(ibm%momentum_change)) / momentum_scale, 1.0e-12_wp, &
                       trim(couplings(trial))//'_'//trim(shapes(body_kind))//'_no_momentum_added')
      call check(sum(ibm%geometry%component(:)%n_ghost) > 100, trim(couplings(trial))//'_'// &
                 trim(shapes(body_kind))//'_has_ghost_nodes')
      if (couplings(trial) == 'implicit') call check_below(real(report%sweeps, wp), 3.0_wp, &
          'implicit_'//trim(shapes(body_kind))//'_converges_at_once_on_exact_field')
    end do
  end do
  call test_finish()

contains

  !> Component c of U + Omega x (x - X) at every node of the field, halos included.
  subroutine fill_rigid(c, field)
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: x(3), r(3), full(3)
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          x = node_position(grid, c, i, j, k)
          r = x - bodies(1)%centre
          full = velocity(:, 1) + [angular_velocity(2, 1) * r(3) - angular_velocity(3, 1) * r(2), &
                                   angular_velocity(3, 1) * r(1) - angular_velocity(1, 1) * r(3), &
                                   angular_velocity(1, 1) * r(2) - angular_velocity(2, 1) * r(1)]
          field(i, j, k) = full(c)
        end do
      end do
    end do
  end subroutine fill_rigid
end program test_immersed_boundary
