// uPlot charts whose canvases the CPU draws. Chrome rasterises a 2D canvas on the GPU unless the
// page says it will read it back; where the GPU is software (SwiftShader, these machines), a live
// run's charts, redrawn four times a second, kept the compositor at 7 frames/s on one core, and
// with the canvases drawn by the CPU at 34 (host_sim/view/README.md, "Live: `scopekin simulate --view`").
import uPlot from 'uplot';

/// new uPlot(options, data, container), its 2D contexts created with willReadFrequently (the
/// hint that moves a canvas to the CPU; uPlot takes its context in the constructor).
export function makeChart(options, data, container) {
  const getContext = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function cpuContext(type, attributes) {
    return type === '2d' ? getContext.call(this, type, { ...attributes, willReadFrequently: true }) : getContext.call(this, type, attributes);
  };
  try {
    return new uPlot(options, data, container);
  } finally {
    HTMLCanvasElement.prototype.getContext = getContext;
  }
}
