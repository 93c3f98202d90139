function h = quadcosim_plot(r, varargin)
%QUADCOSIM_PLOT  Plot signals of a quadcosim run against time, labelled with their units.
%   quadcosim_plot(r, 'IMU.acc')                 a vector: one curve per component
%   quadcosim_plot(r, 'IMU.gyro_x', 'IMU.gyro_y') several signals on one axes
%   r is the struct of QUADCOSIM_LOAD. Returns the line handles.
%
%   See also QUADCOSIM_LOAD.
  for k = 1:numel(varargin)  % every name checked before anything is drawn
    parts = strsplit(varargin{k}, '.');
    if numel(parts) ~= 2 || ~isfield(r, parts{1}) || ~isfield(r.(parts{1}), parts{2})
      error('quadcosim_plot:signal', 'no recorded signal %s (write Block.signal, e.g. IMU.acc_x)', varargin{k});
    end
  end
  h = [];
  labels = {};
  unit = '';
  held = ishold;
  hold on
  for k = 1:numel(varargin)
    name = varargin{k};
    parts = strsplit(name, '.');
    values = r.(parts{1}).(parts{2});
    values = reshape(values, size(values, 1), []);
    h = [h; plot(r.time, values)]; %#ok<AGROW>
    for c = 1:size(values, 2)
      if size(values, 2) > 1
        labels{end + 1} = sprintf('%s(:, %d)', name, c); %#ok<AGROW>
      else
        labels{end + 1} = name; %#ok<AGROW>
      end
    end
    unit = r.units.(parts{1}).(parts{2});
  end
  if ~held
    hold off
  end
  xlabel('time (s)');
  ylabel(sprintf('%s (%s)', strjoin(varargin, ', '), unit));
  legend(labels, 'Interpreter', 'none', 'Location', 'eastoutside');
  grid on
end
