! checks: 3
!> The pressure of the sealed cells (immersed_pressure_extension) visits only each body's box of
!> cells within 3 of its solid nodes and keeps the open/sealed flags between steps. After every step
!> of moving bodies it must give what the rule of docs/theory.md ("Immersed boundary: moving
!> bodies") gives evaluated here from scratch over the whole grid: a cell is open when one of its six
!> faces is a fluid node; an open cell keeps its pressure; a sealed cell with open neighbours N1 = C + e
!> takes the mean of 2 p(N1) - p(N1 + e) (N1 + e open) or p(N1) (N1 + e sealed); a sealed cell without
!> open neighbours keeps its pressure. Seven bodies (needles, disks, spheres; two pairs near contact, one
!> across the periodic boundary in every direction, one too small to hold a node, which moves the
!> bands of the bodies after it down a place) move a fifth of a cell and turn a little each step over
!> 6 steps on a 32^3 grid (1 rank), the pressure a new random field each step. The same
!> arithmetic in the same order: agreement to 1e-14 of the pressure scale (round-off only).
program test_immersed_pressure_extension
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, quaternion_from_axis_angle, quaternion_product
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t, node_fluid
  use immersed_boundary, only: immersed_boundary_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_pressure_extension, only: ibm_extend_pressure
  use test_framework, only: test_start, test_finish, check_below, check_above
  implicit none
  integer, parameter :: n_bodies = 7
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_boundary_t) :: ibm
  type(immersed_body_t) :: bodies(n_bodies)
  real(wp), allocatable :: pressure(:, :, :), before(:, :, :), expected(:, :, :)
  real(wp) :: box(3), direction(3), velocity(3, n_bodies), angular_velocity(3, n_bodies), worst, open_change
  integer :: step, n, extended, nx, ny, nz

  call parallel_start()
  call test_start('immersed_pressure_extension')
  call stream_seed(stream, 53_i8, stream_id=3)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  nx = grid%nx; ny = grid%ny; nz = grid%nz
  call allocate_field(grid, pressure)
  box = [grid%lx, grid%ly, grid%lz]
  ibm%settings%fluid_density = 1000.0_wp
  do n = 1, n_bodies
    select case (mod(n, 3))
    case (1)
      bodies(n)%shape = make_spheroid('needle', 2.5_wp * grid%dx, 1.0_wp, 3.0_wp)
    case (2)
      bodies(n)%shape = make_spheroid('disk', 3.0_wp * grid%dx, 1.0_wp, 2.0_wp)
    case default
      bodies(n)%shape = make_spheroid('sphere', 2.5_wp * grid%dx, 1.0_wp)
    end select
    bodies(n)%orientation = random_orientation(stream)
    bodies(n)%centre = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    velocity(:, n) = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    angular_velocity(:, n) = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
  end do
  bodies(1)%centre = [0.0_wp, 0.0_wp, 0.0_wp]      ! across the periodic boundary along every axis
  ! A body with no node (a sphere of a tenth of a cell at rest at a cell centre, half a cell from
  ! every velocity node) before the last: the bands of the bodies after it move down one place.
  bodies(6)%shape = make_spheroid('sphere', 0.1_wp * grid%dx, 1.0_wp)
  bodies(6)%centre = [10.5_wp, 20.5_wp, 5.5_wp] * grid%dx
  velocity(:, 6) = 0.0_wp
  do n = 2, 4, 2                                   ! two pairs near contact
    direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    bodies(n + 1)%centre = modulo(bodies(n)%centre + direction / norm2(direction) * 1.1_wp * &
                                  (max(bodies(n)%shape%a, bodies(n)%shape%b) + max(bodies(n + 1)%shape%a, &
                                  bodies(n + 1)%shape%b)), box)
  end do
  worst = 0
  extended = 0
  do step = 1, 6
    do n = 1, n_bodies   ! a fifth of a cell along each axis at most, and a small turn
      if (n /= 6) bodies(n)%centre = modulo(bodies(n)%centre + 0.2_wp * grid%dx * velocity(:, n) / &
                                            maxval(abs(velocity(:, n))), box)
      bodies(n)%orientation = quaternion_product(quaternion_from_axis_angle(angular_velocity(:, n), 0.05_wp), &
                                                 bodies(n)%orientation)
    end do
    call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, .true.)
    call random_pressure(pressure)
    before = pressure
    call ibm_extend_pressure(ibm, grid, pressure)
    expected = reference_extension(before)
    worst = max(worst, maxval(abs(pressure(1:nx, 1:ny, 1:nz) - expected)))
    extended = extended + count(abs(pressure(1:nx, 1:ny, 1:nz) - before(1:nx, 1:ny, 1:nz)) > 1.0e-3_wp)
  end do
  ! The kept flags: those of the last step against the ones from scratch.
  open_change = maxval(abs(ibm%cell_open(1:nx, 1:ny, 1:nz) - open_flags()))
  print '(a,es10.3,a,i0,a,es10.3)', 'largest |p - p_reference| / pressure scale ', worst, '; cells extended ', &
      extended, '; largest open-flag difference ', open_change
  call check_below(worst, 1.0e-14_wp, 'extension_matches_the_rule_from_scratch_every_step')
  call check_below(open_change, 0.5_wp, 'kept_open_flags_match_the_status')
  call check_above(real(extended, wp), 100.0_wp, 'sealed_cells_are_extended')
  call test_finish()

contains

  !> Uniform random pressure in [-1, 1] (scale 1) on the whole grid with its periodic halos.
  subroutine random_pressure(field)
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    do k = 1, nz
      do j = 1, ny
        do i = 1, nx
          field(i, j, k) = 2.0_wp * stream_uniform(stream) - 1.0_wp
        end do
      end do
    end do
    field(0, :, :) = field(nx, :, :); field(nx + 1, :, :) = field(1, :, :)
    field(:, 0, :) = field(:, ny, :); field(:, ny + 1, :) = field(:, 1, :)
    field(:, :, 0) = field(:, :, nz); field(:, :, nz + 1) = field(:, :, 1)
  end subroutine random_pressure

  !> 1 where a cell has a fluid face, else 0, over the whole grid (1 rank: the status planes 0 and
  !> nz + 1 are the periodic copies).
  function open_flags() result(open)
    real(wp) :: open(nx, ny, nz)
    integer :: i, j, k
    associate (su => ibm%geometry%component(1)%status, sv => ibm%geometry%component(2)%status, &
               sw => ibm%geometry%component(3)%status)
      do k = 1, nz
        do j = 1, ny
          do i = 1, nx
            open(i, j, k) = merge(1.0_wp, 0.0_wp, su(i - 1, j, k) == node_fluid .or. su(i, j, k) == node_fluid .or. &
                                  sv(i, j - 1, k) == node_fluid .or. sv(i, j, k) == node_fluid .or. &
                                  sw(i, j, k - 1) == node_fluid .or. sw(i, j, k) == node_fluid)
          end do
        end do
      end do
    end associate
  end function open_flags

  !> The extension rule evaluated over every cell (same order of the terms: x+, x-, y+, y-, z+, z-).
  function reference_extension(p) result(q)
    real(wp), intent(in) :: p(0:, 0:, 0:)
    real(wp) :: q(nx, ny, nz), open(nx, ny, nz), total
    integer, parameter :: step_x(6) = [1, -1, 0, 0, 0, 0], step_y(6) = [0, 0, 1, -1, 0, 0], step_z(6) = [0, 0, 0, 0, 1, -1]
    integer :: i, j, k, d, count, i1, j1, k1, i2, j2, k2
    open = open_flags()
    q = p(1:nx, 1:ny, 1:nz)
    do k = 1, nz
      do j = 1, ny
        do i = 1, nx
          if (open(i, j, k) > 0.5_wp) cycle
          total = 0
          count = 0
          do d = 1, 6
            i1 = cell(i + step_x(d), nx); j1 = cell(j + step_y(d), ny); k1 = cell(k + step_z(d), nz)
            i2 = cell(i + 2 * step_x(d), nx); j2 = cell(j + 2 * step_y(d), ny); k2 = cell(k + 2 * step_z(d), nz)
            if (open(i1, j1, k1) < 0.5_wp) cycle
            if (open(i2, j2, k2) > 0.5_wp) then
              total = total + (2.0_wp * p(i1, j1, k1) - p(i2, j2, k2))
            else
              total = total + p(i1, j1, k1)
            end if
            count = count + 1
          end do
          if (count > 0) q(i, j, k) = total / count
        end do
      end do
    end do
  end function reference_extension

  pure integer function cell(i, n)
    integer, intent(in) :: i, n
    cell = modulo(i - 1, n) + 1
  end function cell
end program test_immersed_pressure_extension
