! ranks: 2
! checks: 8
!> Unit tests of field_output on 2 ranks: snapshot files hold the fields bit for bit in the (nx, ny, nz)
!> layout (h5dump shows (nz, ny, nx)); fields.xdmf is valid XML, lists every complete snapshot in step
!> order with its time, places each staggered field on the grid of its MAC positions, and references
!> datasets that exist with the shapes it states (checked with python3's xml.dom.minidom and h5dump,
!> hdf5-tools); snapshots after the current step (left by a killed run) are left out.
program test_field_output
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use run_directory, only: prepare_run_directory, run_file
  use field_output, only: field_snapshot_t, field_snapshot_begin, field_snapshot_add, field_snapshot_end, &
                          write_field_snapshot, at_cell_centre, at_x_face, at_z_face
  use hdf5_files, only: h5_file_t, h5_open, h5_close, h5_finalize
  use hdf5_datasets, only: h5_read_scalar, h5_read_slab, h5_read_array, h5_read_string
  use file_system, only: file_exists
  use parallel_env, only: parallel_start, my_rank, n_ranks, barrier, is_root
  use test_framework, only: test_start, test_finish, check
  implicit none
  integer, parameter :: nx = 4, ny = 3, nz = 6
  real(wp), parameter :: lengths(3) = [2.0_wp, 0.9_wp, 3.6_wp]
  type(agglo_config_t) :: cfg
  type(field_snapshot_t) :: snapshot
  type(h5_file_t) :: file
  real(wp), allocatable :: p(:,:,:), u(:,:,:), w(:,:,:), stack(:,:,:,:), back(:,:,:)
  character(len=:), allocatable :: names
  real(wp) :: time
  integer :: nz_local, z_offset, i, j, k, status
  logical :: same

  call parallel_start()
  call test_start('field_output')
  cfg%output%directory = 'test_field_output_run'
  cfg%run%overwrite = .true.
  if (is_root()) call execute_command_line('rm -rf test_field_output_run', exitstat=status)
  call barrier()
  call prepare_run_directory(cfg)

  nz_local = nz / n_ranks
  z_offset = my_rank * nz_local
  allocate(p(nx, ny, nz_local), u(nx, ny, nz_local), w(nx, ny, nz_local))
  do k = 1, nz_local
    do j = 1, ny
      do i = 1, nx
        p(i, j, k) = i + 10 * j + 100 * (k + z_offset)
        u(i, j, k) = cos(real(i * j + k + z_offset, wp))
        w(i, j, k) = -p(i, j, k) / 7.0_wp
      end do
    end do
  end do

  ! A snapshot of a killed run's future (step 20): must not appear in the XDMF of the run at step 15.
  call write_field_snapshot([character(len=1) :: 'p'], [character(len=6) :: at_cell_centre], &
                            reshape(p, [nx, ny, nz_local, 1]), z_offset, [nx, ny, nz], lengths, 9.0_wp, 20_i8)
  ! Step 0 with the incremental interface, step 10 with the stack interface, then step 15.
  call field_snapshot_begin(snapshot, 0, 0.0_wp, [nx, ny, nz], lengths)
  call field_snapshot_add(snapshot, 'p', p, z_offset, at_cell_centre)
  call field_snapshot_add(snapshot, 'u', u, z_offset, at_x_face)
  call field_snapshot_add(snapshot, 'w', w, z_offset, at_z_face)
  call field_snapshot_end(snapshot)
  allocate(stack(nx, ny, nz_local, 3))
  stack(:, :, :, 1) = 2 * p
  stack(:, :, :, 2) = u
  stack(:, :, :, 3) = w
  call write_field_snapshot([character(len=1) :: 'p', 'u', 'w'], [character(len=6) :: at_cell_centre, at_x_face, &
                            at_z_face], stack, z_offset, [nx, ny, nz], lengths, 0.5_wp, 10)
  call write_field_snapshot([character(len=1) :: 'p', 'u', 'w'], [character(len=6) :: at_cell_centre, at_x_face, &
                            at_z_face], stack, z_offset, [nx, ny, nz], lengths, 0.75_wp, 15_i8)

  call check(file_exists(run_file('fields_0000000000.h5')) .and. file_exists(run_file('fields_0000000010.h5')) &
             .and. .not. file_exists(run_file('fields_0000000010.h5.tmp')), 'snapshot_files_complete')

  ! Bit-for-bit contents, read back on another decomposition (whole array on every rank).
  call h5_open(file, run_file('fields_0000000010.h5'), writable=.false.)
  allocate(back(nx, ny, nz))
  call h5_read_slab(file, 'fields/u', back, 0, [nx, ny, nz])
  same = all(back(:, :, z_offset + 1:z_offset + nz_local) == u)
  call h5_read_slab(file, 'fields/p', back, 0, [nx, ny, nz])
  same = same .and. all(back(:, :, z_offset + 1:z_offset + nz_local) == 2 * p)
  call h5_read_scalar(file, 'time', time)
  call h5_read_string(file, 'field_names', names)
  call h5_close(file)
  call check(same, 'snapshot_fields_bit_exact')
  call check(time == 0.5_wp .and. names == 'p u w', 'snapshot_metadata', names)

  if (is_root()) then
    call write_checker('check_fields_xdmf.py')
    call execute_command_line('python3 check_fields_xdmf.py test_field_output_run xml', exitstat=status)
    call check(status == 0, 'xdmf_is_valid_xml', 'python3 xml.dom.minidom.parse')
    call execute_command_line('python3 check_fields_xdmf.py test_field_output_run content', exitstat=status)
    call check(status == 0, 'xdmf_lists_snapshots_in_order_with_times', 'steps 0 10 15, not the stale 20')
    call execute_command_line('python3 check_fields_xdmf.py test_field_output_run staggering', exitstat=status)
    call check(status == 0, 'xdmf_origins_at_mac_positions', 'p (dx/2,dy/2,dz/2), u (dx,..), w (..,dz)')
    call execute_command_line('python3 check_fields_xdmf.py test_field_output_run datasets', exitstat=status)
    call check(status == 0, 'xdmf_datasets_exist_with_stated_shape', 'h5dump -H: (nz, ny, nx) = (6, 3, 4)')
    call execute_command_line('python3 check_fields_xdmf.py test_field_output_run values', exitstat=status)
    call check(status == 0, 'h5dump_sees_x_fastest', 'p(i,j,k) = i + 10 j + 100 k at h5dump [k-1][j-1][i-1]')
    call execute_command_line('rm -rf test_field_output_run check_fields_xdmf.py', exitstat=status)
  end if
  call barrier()
  call h5_finalize()
  call test_finish()

contains

  !> A python3 checker of fields.xdmf (stdlib only, plus h5dump from hdf5-tools).
  subroutine write_checker(path)
    character(len=*), intent(in) :: path
    integer :: unit
    open(newunit=unit, file=path, status='replace', action='write')
    write(unit, '(a)') 'import sys, subprocess, re, xml.dom.minidom as md'
    write(unit, '(a)') 'run, mode = sys.argv[1], sys.argv[2]'
    write(unit, '(a)') 'doc = md.parse(run + "/fields.xdmf")'
    write(unit, '(a)') 'def kids(e, tag): return [c for c in e.childNodes if c.nodeType == 1 and c.tagName == tag]'
    write(unit, '(a)') 'domain = kids(doc.documentElement, "Domain")[0]'
    write(unit, '(a)') 'temporal = kids(domain, "Grid")[0]'
    write(unit, '(a)') 'assert temporal.getAttribute("CollectionType") == "Temporal"'
    write(unit, '(a)') 'steps = kids(temporal, "Grid")'
    write(unit, '(a)') 'if mode == "content":'
    write(unit, '(a)') '    names = [g.getAttribute("Name") for g in steps]'
    write(unit, '(a)') '    times = [float(kids(g, "Time")[0].getAttribute("Value")) for g in steps]'
    write(unit, '(a)') '    print(names, times)'
    write(unit, '(a)') '    assert names == ["step_0000000000", "step_0000000010", "step_0000000015"], names'
    write(unit, '(a)') '    assert times == [0.0, 0.5, 0.75], times'
    write(unit, '(a)') 'if mode == "staggering":'
    write(unit, '(a)') '    dx, dy, dz = 2.0 / 4, 0.9 / 3, 3.6 / 6'
    write(unit, '(a)') '    want = {"centre": [dz/2, dy/2, dx/2], "x_face": [dz/2, dy/2, dx], "z_face": [dz, dy/2, dx/2]}'
    write(unit, '(a)') '    for g in kids(steps[1], "Grid"):'
    write(unit, '(a)') '        items = kids(kids(g, "Geometry")[0], "DataItem")'
    write(unit, '(a)') '        origin = [float(x) for x in items[0].firstChild.data.split()]'
    write(unit, '(a)') '        spacing = [float(x) for x in items[1].firstChild.data.split()]'
    write(unit, '(a)') '        print(g.getAttribute("Name"), origin, spacing)'
    write(unit, '(a)') '        assert all(abs(a - b) < 1e-15 for a, b in zip(origin, want[g.getAttribute("Name")]))'
    write(unit, '(a)') '        assert all(abs(a - b) < 1e-15 for a, b in zip(spacing, [dz, dy, dx]))'
    write(unit, '(a)') '    grids = sorted(g.getAttribute("Name") for g in kids(steps[1], "Grid"))'
    write(unit, '(a)') '    assert grids == ["centre", "x_face", "z_face"], grids'
    write(unit, '(a)') 'if mode == "datasets":'
    write(unit, '(a)') '    count = 0'
    write(unit, '(a)') '    for item in doc.getElementsByTagName("DataItem"):'
    write(unit, '(a)') '        if item.getAttribute("Format") != "HDF": continue'
    write(unit, '(a)') '        name, dataset = item.firstChild.data.strip().split(":")'
    write(unit, '(a)') '        out = subprocess.run(["h5dump", "-H", "-d", dataset, run + "/" + name],'
    write(unit, '(a)') '                             capture_output=True, text=True)'
    write(unit, '(a)') '        assert out.returncode == 0, (name, dataset, out.stderr)'
    write(unit, '(a)') '        dims = re.search(r"SIMPLE \{ \( ([0-9, ]+) \)", out.stdout).group(1).replace(",", " ").split()'
    write(unit, '(a)') '        assert dims == item.getAttribute("Dimensions").split(), (dims, item.getAttribute("Dimensions"))'
    write(unit, '(a)') '        count += 1'
    write(unit, '(a)') '    print(count, "datasets checked")'
    write(unit, '(a)') '    assert count == 9'
    write(unit, '(a)') 'if mode == "values":'
    write(unit, '(a)') '    out = subprocess.run(["h5dump", "-d", "/fields/p", "-s", "4,2,3", "-c", "1,1,1", "-y",'
    write(unit, '(a)') '                          run + "/fields_0000000000.h5"], capture_output=True, text=True).stdout'
    write(unit, '(a)') '    value = float(re.search(r"DATA \{\s*([-0-9.eE+]+)", out).group(1))'
    write(unit, '(a)') '    print(value)'
    write(unit, '(a)') '    assert value == 4 + 10 * 3 + 100 * 5'
    close(unit)
  end subroutine write_checker
end program test_field_output
