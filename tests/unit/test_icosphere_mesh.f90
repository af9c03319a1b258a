! checks: 65
!> Tests of icosphere_mesh: counts, closed and consistently oriented surface, vertices on the
!> spheroid, outward unit normals, and second-order convergence of volume and area to the analytic
!> spheroid with the subdivision level (edge length halves per level: error ratio -> 4); the
!> 320-face volume deficit and face-centre depth quoted in docs/physics.md section 1.
program test_icosphere_mesh
  use agglo_kinds, only: wp
  use spheroid, only: spheroid_t, make_spheroid, implicit_function, surface_area
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh, mesh_volume, mesh_area, icosphere_face_count
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp
  type(spheroid_t) :: shapes(4)
  type(icosphere_mesh_t) :: mesh
  real(wp) :: volume_error(0:4), area_error(0:4), worst, depth, ratio_v, ratio_a
  integer :: i, level, f, closed_errors
  character(len=24) :: label

  call test_start('icosphere_mesh')
  shapes = [make_spheroid('sphere', radius, density), make_spheroid('needle', radius, density), &
            make_spheroid('disk', radius, density), make_spheroid('needle', radius, density, 20.0_wp)]

  do i = 1, size(shapes)
    write(label, '(a,a,f0.2)') trim(shapes(i)%shape), '_', shapes(i)%aspect_ratio
    do level = 0, 4
      call build_icosphere_mesh(shapes(i), level, mesh)
      volume_error(level) = 1.0_wp - mesh_volume(mesh) / shapes(i)%volume
      area_error(level) = 1.0_wp - mesh_area(mesh) / surface_area(shapes(i))
      if (i == 1) then
        call check_equal(mesh%n_faces, icosphere_face_count(level), 'face_count_level_'//achar(48 + level))
        ! Closed triangulated sphere: V = F/2 + 2 (Euler characteristic 2).
        call check_equal(mesh%n_vertices, mesh%n_faces / 2 + 2, 'euler_vertices_level_'//achar(48 + level))
      end if
      ! Every directed edge appears once and its reverse once: closed, consistently oriented.
      closed_errors = directed_edge_errors(mesh)
      call check_equal(closed_errors, 0, 'closed_oriented_'//trim(label)//'_level_'//achar(48 + level))
      worst = 0.0_wp
      do f = 1, mesh%n_vertices
        worst = max(worst, abs(implicit_function(shapes(i), mesh%vertices(:, f))))
      end do
      do f = 1, mesh%n_faces
        ! Unit, outward (centroid side) normals; positive areas.
        worst = max(worst, abs(norm2(mesh%face_normals(:, f)) - 1.0_wp))
        if (dot_product(mesh%face_normals(:, f), mesh%face_centres(:, f)) <= 0.0_wp) worst = 1.0_wp
        if (mesh%face_areas(f) <= 0.0_wp) worst = 1.0_wp
      end do
      call check_below(worst, 1.0e-14_wp, 'vertices_on_surface_normals_outward_'//trim(label)//'_level_'//achar(48 + level))
    end do
    ! Second order in the edge length: error ratio between levels -> 4 (measured on the two finest pairs).
    ratio_v = volume_error(3) / volume_error(4)
    ratio_a = area_error(3) / area_error(4)
    write(*, '(2a,5es11.3)') '  volume deficit by level ', trim(label), volume_error
    write(*, '(2a,5es11.3)') '  area deficit by level   ', trim(label), area_error
    write(*, '(a,4f7.3)') '  volume ratios ', volume_error(0:3) / volume_error(1:4)
    write(*, '(a,4f7.3)') '  area ratios   ', area_error(0:3) / area_error(1:4)
    ! Measured 3.983 (volume) and 3.98-3.99 (area) for 1280 -> 5120 faces.
    call check_close(ratio_v, 4.0_wp, 0.02_wp, 'volume_second_order_'//trim(label))
    call check_close(ratio_a, 4.0_wp, 0.02_wp, 'area_second_order_'//trim(label))
    call check(all(volume_error > 0.0_wp) .and. all(area_error > 0.0_wp), 'inscribed_mesh_smaller_'//trim(label))
  end do

  ! docs/physics.md section 1: the 320-face icosphere (level 2) has 3.4% less volume than the spheroid
  ! (the deficit is shape-independent: the affine map (a, b, b) scales both volumes alike), and facet
  ! centres lie up to 1.8% of the radius inside the true surface (sphere).
  call build_icosphere_mesh(shapes(1), 2, mesh)
  call check_close(1.0_wp - mesh_volume(mesh) / shapes(1)%volume, 0.034_wp, 0.03_wp, 'level2_volume_deficit_3.4_percent')
  call build_icosphere_mesh(shapes(3), 2, mesh)
  call check_close(1.0_wp - mesh_volume(mesh) / shapes(3)%volume, 0.034_wp, 0.03_wp, 'level2_disk_volume_deficit_3.4_percent')
  call build_icosphere_mesh(shapes(1), 2, mesh)
  depth = 0.0_wp
  do f = 1, mesh%n_faces
    depth = max(depth, radius - norm2(mesh%face_centres(:, f)))
  end do
  call check_close(depth / radius, 0.018_wp, 0.05_wp, 'level2_face_centre_depth_1.8_percent_of_radius')

  call test_finish()

contains

  !> Number of directed edges (i -> j) that do not appear exactly once, or whose reverse does not.
  integer function directed_edge_errors(m)
    type(icosphere_mesh_t), intent(in) :: m
    integer, allocatable :: count_forward(:,:)
    integer :: f2, k, a, b
    ! Dense count table is fine up to 2562 vertices (6.6 M small integers at level 4).
    allocate(count_forward(m%n_vertices, m%n_vertices))
    count_forward = 0
    do f2 = 1, m%n_faces
      do k = 1, 3
        a = m%faces(k, f2)
        b = m%faces(mod(k, 3) + 1, f2)
        count_forward(a, b) = count_forward(a, b) + 1
      end do
    end do
    directed_edge_errors = count(count_forward > 1) + count(count_forward /= transpose(count_forward))
  end function directed_edge_errors

end program test_icosphere_mesh
