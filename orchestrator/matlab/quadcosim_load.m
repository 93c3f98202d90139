function r = quadcosim_load(run)
%QUADCOSIM_LOAD  Read the results of a quadcosim run into one struct.
%   r = quadcosim_load('results/tp') reads results/tp/results.mat (written by
%   `quadcosim run ... --format npz,mat`); r = quadcosim_load('x/results.mat') reads that file.
%
%   r.time            N x 1 time (s)
%   r.IMU.acc_x       N x 1, one field per recorded signal, one struct per block
%   r.IMU.acc         N x 3, each vector also as one array (r.IMU.R_reel is N x 3 x 3)
%   r.units.IMU.acc_x 'm/s2', the unit of every signal ('s' for time)
%   r.options         the scenario's options as used
%   r.meta            scenario name, step dt_s (s), decimation, error message, faults
%
%   See also QUADCOSIM_PLOT.
  if exist(run, 'dir')
    file = fullfile(run, 'results.mat');
  else
    file = run;
  end
  if ~exist(file, 'file')
    error('quadcosim_load:missing', ['%s: no results.mat; run the scenario with ' ...
          '--format npz,mat (or give the .mat file)'], file);
  end
  r = load(file);
  if ~isfield(r, 'time') || ~isfield(r, 'units')
    error('quadcosim_load:format', '%s was not written by quadcosim (no time or units)', file);
  end
  r.time = r.time(:);
end
