! checks: 24
!> The mesh geometry (mesh_distance) and the face-sum loads (immersed_surface_loads) on fields whose
!> loads are known:
!> - closest point on the icosphere of a spheroid against a brute-force search over points sampled
!>   on every face (to the sampling's resolution), the sign of the distance against the inside
!>   test, and for inside points the distance equal to the nearest face plane's (convex mesh);
!> - config_bodies' mesh_level range equals icosphere_mesh's;
!> - the face sum on Stokes' exact fields around a sphere (Stokes 1851; e.g. Happel & Brenner 1965,
!>   sections 4-2 and 4-17), set on the grid nodes, sphere of D/dx = 16 and 32: a sphere translating
!>   at U in fluid at rest, u = U.[(3a/4r)(I + e e) + (a^3/4r^3)(I - 3 e e)], p = (3/2) mu a U.x/r^3,
!>   force -6 pi mu a U; a sphere rotating at Omega, u = (a/r)^3 Omega x x, p = 0, torque
!>   -8 pi mu a^3 Omega. Inside the sphere the same formulas continue the field smoothly (as the
!>   ghost values continue the fluid field) down to r = a/2, the rigid motion below. The linear
!>   pressure extrapolation and the one-sided derivative from probes at h = dx and 2 dx err by
!>   O((h/a)^2) (p ~ 1/r^2 alone gives -6% in p_B at D/dx = 16, a third of the drag), with the
!>   320-face quadrature on top: measured -3.5% (force) and -2.7% (torque) at D/dx = 16, -1.1% and
!>   -0.9% at 32 (observed order 1.6-1.7); bounds 4.5% at 16, 1.5% at 32, order >= 1.4, and the
!>   lateral force and torque below 1e-3 of the main ones.
!> - the mean pressure gradient: with the drive f and no flow the face sum is f V exactly;
!> - field_interpolation's masked interpolation (the face sum's pressure probes): a mask of ones
!>   changes nothing, a masked node's value is ignored, a stencil with no unmasked node falls back
!>   to the plain interpolation.
program test_immersed_surface
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use quaternion, only: random_orientation
  use spheroid, only: spheroid_t, make_spheroid
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh, max_icosphere_level
  use mesh_distance, only: mesh_contains, mesh_body_closest_point
  use spheroid_distance, only: surface_projection_t
  use config_bodies, only: max_mesh_level
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field, x_centre, y_centre, z_centre
  use vector_algebra, only: cross
  use immersed_geometry, only: immersed_body_t, node_position
  use field_interpolation, only: interpolate_at_points, on_cell_centres
  use immersed_surface_loads, only: surface_loads_t, surface_loads_create, surface_loads_compute
  use test_framework, only: test_start, test_finish, check_below, check_above, check_equal, check_close
  implicit none
  type(random_stream_t) :: stream

  call parallel_start()
  call test_start('immersed_surface')
  call stream_seed(stream, 77_i8, stream_id=5)
  call check_equal(max_mesh_level, max_icosphere_level, 'config_mesh_level_range_matches_icosphere')
  call check_mesh_distance()
  call check_stokes_loads()
  call check_masked_interpolation()
  call test_finish()

contains

  subroutine check_mesh_distance()
    type(spheroid_t) :: shape
    type(icosphere_mesh_t) :: mesh
    type(surface_projection_t) :: projection
    real(wp) :: p(3), sample(3), brute, plane, worst_brute, worst_gap, worst_plane, worst_normal, longest_edge
    integer :: trial, f, s, t, sign_errors
    integer, parameter :: samples = 12
    shape = make_spheroid('needle', 1.0_wp, 1000.0_wp, 3.0_wp)
    call build_icosphere_mesh(shape, 2, mesh)
    worst_brute = 0; worst_gap = 0; worst_plane = 0; worst_normal = 0; sign_errors = 0
    longest_edge = 0
    do f = 1, mesh%n_faces
      do s = 1, 3
        longest_edge = max(longest_edge, norm2(mesh%vertices(:, mesh%faces(s, f)) - &
                                               mesh%vertices(:, mesh%faces(mod(s, 3) + 1, f))))
      end do
    end do
    do trial = 1, 200
      p = [2.0_wp * shape%a, 2.0_wp * shape%b, 2.0_wp * shape%b] * &
          ([stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] - 0.5_wp) * 1.4_wp
      projection = mesh_body_closest_point(mesh, p)
      ! Brute force: points of a barycentric lattice on every face.
      brute = huge(1.0_wp)
      plane = huge(1.0_wp)
      do f = 1, mesh%n_faces
        associate (a => mesh%vertices(:, mesh%faces(1, f)), b => mesh%vertices(:, mesh%faces(2, f)), &
                   c => mesh%vertices(:, mesh%faces(3, f)))
          do s = 0, samples
            do t = 0, samples - s
              sample = a + (real(s, wp) * (b - a) + real(t, wp) * (c - a)) / samples
              brute = min(brute, norm2(p - sample))
            end do
          end do
        end associate
        plane = min(plane, abs(dot_product(p - mesh%face_centres(:, f), mesh%face_normals(:, f))))
      end do
      ! No lattice point is nearer than the closest point; the lattice misses it by less than a
      ! lattice edge.
      worst_brute = max(worst_brute, abs(projection%signed_distance) - brute)
      worst_gap = max(worst_gap, brute - abs(projection%signed_distance))
      if ((projection%signed_distance < 0.0_wp) .neqv. mesh_contains(mesh, p)) sign_errors = sign_errors + 1
      if (projection%signed_distance < 0.0_wp) then
        worst_plane = max(worst_plane, abs(abs(projection%signed_distance) - plane))
        worst_normal = max(worst_normal, norm2(projection%point - (p - projection%signed_distance * projection%normal)))
      end if
    end do
    call check_below(worst_brute, 1.0e-12_wp, 'mesh_closest_point_not_beaten_by_brute_force')
    call check_below(worst_gap, longest_edge / samples, 'mesh_closest_point_within_lattice_of_brute_force')
    call check_equal(sign_errors, 0, 'mesh_signed_distance_sign_is_inside_test')
    call check_below(worst_plane, 1.0e-12_wp, 'mesh_inside_distance_is_nearest_face_plane')
    call check_below(worst_normal, 1.0e-12_wp, 'mesh_inside_point_is_foot_along_face_normal')
  end subroutine check_mesh_distance

  subroutine check_stokes_loads()
    integer, parameter :: resolutions(2) = [32, 64]
    real(wp) :: errors(2, 2)
    integer :: r
    character(len=160) :: text
    do r = 1, 2
      call stokes_case(resolutions(r), errors(:, r))
      write(text, '(a,i0,a,f7.3,a,f7.3,a)') 'grid ', resolutions(r), '^3 (D/dx = ', resolutions(r) / 2.0_wp, &
          '): face-sum force error ', 100 * errors(1, r), '%'
      write(text, '(a,a,f7.3,a)') trim(text), ', torque error ', 100 * errors(2, r), '%'
      print '(a)', trim(text)
    end do
    call check_below(abs(errors(1, 1)), 0.045_wp, 'translating_sphere_force_4p5pc_at_D16')
    call check_below(abs(errors(2, 1)), 0.045_wp, 'rotating_sphere_torque_4p5pc_at_D16')
    call check_below(abs(errors(1, 2)), 0.015_wp, 'translating_sphere_force_1p5pc_at_D32')
    call check_below(abs(errors(2, 2)), 0.015_wp, 'rotating_sphere_torque_1p5pc_at_D32')
    call check_above(log(abs(errors(1, 1)) / abs(errors(1, 2))) / log(2.0_wp), 1.4_wp, 'force_error_order_above_1p4')
    call check_above(log(abs(errors(2, 1)) / abs(errors(2, 2))) / log(2.0_wp), 1.4_wp, 'torque_error_order_above_1p4')
  end subroutine check_stokes_loads

  !> Relative errors of the face-sum force (translating) and torque (rotating) on a sphere of
  !> radius L/4 on an n^3 grid (D/dx = n/2), 320 faces, random orientation and sub-cell position.
  subroutine stokes_case(n, errors)
    integer, intent(in) :: n
    real(wp), intent(out) :: errors(2)
    real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp
    type(fluid_grid_t) :: grid
    type(surface_loads_t) :: loads
    type(immersed_body_t) :: bodies(1)
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :), p(:, :, :)
    real(wp) :: velocity(3, 1), angular_velocity(3, 1), force(3, 1), torque(3, 1), radius, mu, exact(3)
    real(wp) :: drive(3)
    integer :: motion
    call grid_create(grid, n, n, n, box, box, box)
    call allocate_field(grid, u); call allocate_field(grid, v); call allocate_field(grid, w)
    call allocate_field(grid, p)
    radius = 0.25_wp * box
    mu = density * viscosity
    bodies(1)%shape = make_spheroid('sphere', radius, density)
    bodies(1)%centre = 0.5_wp * box + [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] * grid%dx
    bodies(1)%orientation = random_orientation(stream)
    call surface_loads_create(loads, [bodies(1)%shape])
    drive = 0
    do motion = 1, 2
      velocity = 0
      angular_velocity = 0
      if (motion == 1) then
        velocity(:, 1) = [1.0e-4_wp, -0.5e-4_wp, 0.3e-4_wp]
      else
        angular_velocity(:, 1) = [0.2_wp, 0.4_wp, -0.3_wp]
      end if
      call fill(grid, bodies(1)%centre, radius, mu, velocity(:, 1), angular_velocity(:, 1), 1, u)
      call fill(grid, bodies(1)%centre, radius, mu, velocity(:, 1), angular_velocity(:, 1), 2, v)
      call fill(grid, bodies(1)%centre, radius, mu, velocity(:, 1), angular_velocity(:, 1), 3, w)
      call fill(grid, bodies(1)%centre, radius, mu, velocity(:, 1), angular_velocity(:, 1), 4, p)
      call surface_loads_compute(loads, grid, bodies, velocity, angular_velocity, u, v, w, p, viscosity, density, &
                                 drive, force, torque)
      if (motion == 1) then
        exact = -6.0_wp * pi * mu * radius * velocity(:, 1)
        errors(1) = dot_product(force(:, 1), exact) / dot_product(exact, exact) - 1.0_wp
        call check_below(norm2(force(:, 1) - dot_product(force(:, 1), exact) / dot_product(exact, exact) * exact), &
                         1.0e-3_wp * norm2(exact), 'translating_force_along_velocity_'//trim(grid_text(n)))
      else
        exact = -8.0_wp * pi * mu * radius**3 * angular_velocity(:, 1)
        errors(2) = dot_product(torque(:, 1), exact) / dot_product(exact, exact) - 1.0_wp
        call check_below(norm2(torque(:, 1) - dot_product(torque(:, 1), exact) / dot_product(exact, exact) * exact), &
                         1.0e-3_wp * norm2(exact), 'rotating_torque_along_omega_'//trim(grid_text(n)))
      end if
    end do
    ! The mean pressure gradient alone: fluid at rest, periodic pressure zero, F = f V.
    velocity = 0; angular_velocity = 0; u = 0; v = 0; w = 0; p = 0
    drive = [3.0_wp, -1.0_wp, 2.0_wp]
    call surface_loads_compute(loads, grid, bodies, velocity, angular_velocity, u, v, w, p, viscosity, density, &
                               drive, force, torque)
    call check_close(force(1, 1), drive(1) * bodies(1)%shape%volume, 1.0e-12_wp, 'mean_gradient_force_is_f_V_'// &
                     trim(grid_text(n)))
    call check_below(norm2(torque(:, 1)), 1.0e-30_wp, 'mean_gradient_no_torque_'//trim(grid_text(n)))
  end subroutine stokes_case

  !> Field `which` (1..3 velocity components on their nodes, 4 pressure at the centres) of the
    !> exact solution, halos included (the box is large enough that the periodic wrap never enters
    !> a probe's stencil).
    subroutine fill(grid, centre, radius, mu, velocity, angular_velocity, which, field)
      type(fluid_grid_t), intent(in) :: grid
      real(wp), intent(in) :: centre(3), radius, mu, velocity(3), angular_velocity(3)
      integer, intent(in) :: which
      real(wp), intent(inout) :: field(0:, 0:, 0:)
      real(wp) :: x(3), e(3), r, value(3), pressure
      integer :: i, j, k
      do k = 0, grid%nz_local + 1
        do j = 0, grid%ny + 1
          do i = 0, grid%nx + 1
            if (which == 4) then
              x = [x_centre(grid, i), y_centre(grid, j), z_centre(grid, k)] - centre
            else
              x = node_position(grid, which, i, j, k) - centre
            end if
            r = norm2(x)
            e = x / r
            if (r <= 0.5_wp * radius) then
              value = velocity + cross(angular_velocity, x)
              pressure = 0
            else
              value = 0.75_wp * radius / r * (velocity + e * dot_product(e, velocity)) + &
                      0.25_wp * (radius / r)**3 * (velocity - 3.0_wp * e * dot_product(e, velocity)) + &
                      (radius / r)**3 * cross(angular_velocity, x)
              pressure = 1.5_wp * mu * radius * dot_product(velocity, x) / r**3
            end if
            if (which == 4) then
              field(i, j, k) = pressure
            else
              field(i, j, k) = value(which)
            end if
          end do
        end do
      end do
    end subroutine fill

  subroutine check_masked_interpolation()
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: field(:, :, :), mask(:, :, :)
    real(wp) :: points(3, 3), plain(3), masked(3)
    integer :: p
    call grid_create(grid, 8, 8, 8, 1.0_wp, 1.0_wp, 1.0_wp)
    call allocate_field(grid, field)
    call allocate_field(grid, mask)
    do p = 1, 3
      points(:, p) = [3.2_wp, 3.4_wp, 3.7_wp] / 8 + 0.1_wp * [stream_uniform(stream), stream_uniform(stream), &
                                                             stream_uniform(stream)] / 8
    end do
    field = 2.0_wp
    field(4, 4, 4) = 100.0_wp     ! the cell centre (3.5, 3.5, 3.5)/8: in every point's stencil
    mask = 1.0_wp
    call interpolate_at_points(grid, field, on_cell_centres, points, plain)
    call interpolate_at_points(grid, field, on_cell_centres, points, masked, mask=mask)
    call check_below(maxval(abs(masked - plain)), 1.0e-14_wp * maxval(abs(plain)), 'mask_of_ones_changes_nothing')
    mask(4, 4, 4) = 0
    call interpolate_at_points(grid, field, on_cell_centres, points, masked, mask=mask)
    call check_below(maxval(abs(masked - 2.0_wp)), 1.0e-13_wp, 'masked_node_is_ignored')
    call check_above(minval(plain), 2.5_wp, 'unmasked_interpolation_sees_the_node')
    mask = 0
    call interpolate_at_points(grid, field, on_cell_centres, points, masked, mask=mask)
    call check_below(maxval(abs(masked - plain)), 1.0e-14_wp * maxval(abs(plain)), 'fully_masked_stencil_falls_back')
  end subroutine check_masked_interpolation

  function grid_text(n) result(text)
    integer, intent(in) :: n
    character(len=12) :: text
    write(text, '(a,i0)') 'n', n
  end function grid_text
end program test_immersed_surface
