!> Agglo main program: read the deck -> prepare the run -> run the scene it switches on.
program agglo
  use agglo_config, only: agglo_config_t
  use config_reader, only: read_config
  use error_handling, only: fatal
  use logger, only: log_open, log_line, log_close
  use parallel_env, only: parallel_start, parallel_stop, n_ranks
  use run_directory, only: prepare_run_directory, run_file
  use run_header, only: log_run_header
  use hdf5_io, only: hdf5_io_finalize
  use resolved_scene, only: run_resolved_scene
  use pair_scene, only: run_pair_scene
  implicit none
  type(agglo_config_t) :: cfg
  character(len=1024) :: deck_path

  call parallel_start()
  if (command_argument_count() /= 1) call fatal('usage: agglo DECK.nml   (run with mpirun -np N for N ranks)')
  call get_command_argument(1, deck_path)

  call read_config(trim(deck_path), n_ranks, cfg)
  call prepare_run_directory(cfg)
  call log_open(run_file('agglo.log'))
  call log_run_header(cfg)

  select case (trim(cfg%scene%fluid))
  case ('resolved')
    call run_resolved_scene(cfg)
  case default
    call run_pair_scene(cfg)
  end select

  call log_line('agglo: run complete; outputs in '//run_file(''))
  call log_close()
  call hdf5_io_finalize()
  call parallel_stop()
end program agglo
