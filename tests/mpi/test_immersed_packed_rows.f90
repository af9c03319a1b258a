! ranks: 2
! checks: 3
!> The Jacobi sweeps run on the ghost rows packed from the records (immersed_imposition, ghost_rows_t:
!> stencil positions in the flattened field and in the neighbours' copied planes, the stencil values
!> gathered once per imposition, then only the ghost corners whose value changed read again and only
!> the rows that read them evaluated again). After each implicit
!> imposition every ghost row, evaluated here from its record, the field and the plane copies as the
!> row is written (docs/theory.md, "Immersed boundary: imposition and loads"),
!>   (1 + kappa w_G) u_G - (1 + kappa) u_B + kappa sum_{j /= G} w_j u_j,
!> must vanish to the sweeps' tolerance: the residual left by the last sweep is kappa times its
!> largest change, at most 4 x 1e-12 of the velocity scale (kappa <= 4 on the fallback rows, whose
!> image point lies at least a quarter cell from B). A wrong position, plane or stale value in the
!> packing leaves residuals of the order of the velocity scale, a row left out of a later sweep
!> residuals of the change it missed (above 4e-12 in all but the last sweeps). A needle and a disk on 2 ranks (z
!> slabs of 16 planes: stencils that reach across the rank boundary and the periodic wrap), 12
!> random placements (one in three near contact: fallback rows), each moved over 3 steps (a new
!> classification and packing each step), random fields and rigid motions.
program test_immersed_packed_rows
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, global_max, global_sum
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, quaternion_from_axis_angle, quaternion_product
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t, ghost_surface_value
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use test_framework, only: test_start, test_finish, check_below, check_above
  implicit none
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_boundary_t) :: ibm
  type(immersed_body_t) :: bodies(2)
  type(imposition_report_t) :: report
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
  real(wp) :: box(3), direction(3), velocity(3, 2), angular_velocity(3, 2), worst, dt
  integer :: p, step, n, off_slab, fallbacks

  call parallel_start()
  call test_start('immersed_packed_rows')
  ! The same stream on every rank: every rank places the same bodies (the fields differ by rank).
  call stream_seed(stream, 47_i8, stream_id=2)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  call allocate_field(grid, u)
  call allocate_field(grid, v)
  call allocate_field(grid, w)
  box = [grid%lx, grid%ly, grid%lz]
  ibm%settings%coupling = 'implicit'
  ibm%settings%tolerance = 1.0e-12_wp
  ibm%settings%max_sweeps = 2000
  ibm%settings%fluid_density = 1000.0_wp
  bodies(1)%shape = make_spheroid('needle', 3.0_wp * grid%dx, 1.0_wp, 3.0_wp)
  bodies(2)%shape = make_spheroid('disk', 3.5_wp * grid%dx, 1.0_wp, 2.0_wp)
  dt = 1.0e-4_wp
  worst = 0
  off_slab = 0
  fallbacks = 0
  do p = 1, 12
    bodies(1)%centre = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    bodies(1)%orientation = random_orientation(stream)
    bodies(2)%orientation = random_orientation(stream)
    direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    direction = direction / norm2(direction)
    if (mod(p, 3) == 0) then   ! near contact (the image-point fallback)
      bodies(2)%centre = bodies(1)%centre + direction * (bodies(1)%shape%a + bodies(2)%shape%b) * 0.8_wp
    else
      bodies(2)%centre = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    end if
    bodies(2)%centre = modulo(bodies(2)%centre, box)
    do n = 1, 2
      velocity(:, n) = 1.0e-3_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      angular_velocity(:, n) = 20.0_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    end do
    do step = 1, 3
      ! A fifth of a cell per step at most along each axis, and a small turn.
      do n = 1, 2
        bodies(n)%centre = modulo(bodies(n)%centre + 0.2_wp * grid%dx * velocity(:, n) / maxval(abs(velocity(:, n))), box)
        bodies(n)%orientation = quaternion_product(quaternion_from_axis_angle(angular_velocity(:, n), 0.05_wp), &
                                                   bodies(n)%orientation)
      end do
      call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, .true.)
      call random_field(u)
      call random_field(v)
      call random_field(w)
      call ibm_impose(ibm, grid, u, v, w, report)
      worst = max(worst, largest_residual(1, u) / report%velocity_scale, largest_residual(2, v) / report%velocity_scale, &
                  largest_residual(3, w) / report%velocity_scale)
    end do
  end do
  print '(a,es10.3,a,i0,a,i0)', 'largest row residual / velocity scale ', global_max(worst), &
      '; ghost rows reading the copied planes ', nint(global_sum(real(off_slab, wp))), '; fallback rows ', &
      nint(global_sum(real(fallbacks, wp)))
  call check_below(global_max(worst), 4.0e-12_wp, 'rows_from_records_hold_after_every_imposition')
  call check_above(global_sum(real(off_slab, wp)), 100.0_wp, 'rows_read_the_copied_planes')
  call check_above(global_sum(real(fallbacks, wp)), 1.0_wp, 'placements_include_fallback_rows')
  call test_finish()

contains

  !> Uniform random values in [-1, 1] mm/s on this rank's planes.
  subroutine random_field(field)
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          field(i, j, k) = 1.0e-3_wp * (2.0_wp * stream_uniform(stream) - 1.0_wp)
        end do
      end do
    end do
  end subroutine random_field

  !> Largest |row residual| over the ghost rows of one component, from the records (m/s).
  real(wp) function largest_residual(component, field) result(largest)
    integer, intent(in) :: component
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer :: g, corner, k
    real(wp) :: neighbours, value, self_weight, residual
    largest = 0
    associate (nodes => ibm%geometry%component(component))
      do g = 1, nodes%n_ghost
        associate (ghost => nodes%ghost(g))
          if (ghost%fallback) fallbacks = fallbacks + 1
          neighbours = 0
          self_weight = 0
          do corner = 1, 8
            if (corner == ghost%self_corner) then
              self_weight = ghost%weight(corner)
              cycle
            end if
            k = ghost%node(3) + ghost%lower_offset(3) + (corner - 1) / 4
            if (k < 1) then
              value = ibm%planes%below(ghost%stencil(1, corner), ghost%stencil(2, corner), k, component)
            else if (k > grid%nz_local) then
              value = ibm%planes%above(ghost%stencil(1, corner), ghost%stencil(2, corner), k, component)
            else
              value = field(ghost%stencil(1, corner), ghost%stencil(2, corner), k)
            end if
            neighbours = neighbours + ghost%weight(corner) * value
          end do
          if (any(.not. ghost%stencil_local)) off_slab = off_slab + 1
          residual = (1.0_wp + ghost%extrapolation * self_weight) * field(ghost%node(1), ghost%node(2), ghost%node(3)) &
                     - (1.0_wp + ghost%extrapolation) * ghost_surface_value(ibm, component, g) &
                     + ghost%extrapolation * neighbours
          largest = max(largest, abs(residual))
        end associate
      end do
    end associate
  end function largest_residual
end program test_immersed_packed_rows
