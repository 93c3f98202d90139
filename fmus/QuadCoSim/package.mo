within ;
package QuadCoSim "Modelica twins of the quadcosim plant FMUs"
  annotation (Documentation(info = "<html>
<p>Each model here has the variable names, causalities, parameters and equations of the FMU of
the same name built from <code>fmus/&lt;Model&gt;/model.c</code>. Conventions: NED inertial
frame, FRD body frame, quaternion scalar first, R(q) = I + 2 q0 S(qv) + 2 S(qv)^2 maps body to
inertial coordinates. Motor numbering (quad-X, PX4): 1 front-right CCW, 2 rear-left CCW,
3 front-left CW, 4 rear-right CW.</p>
<p>The equations are written in scalar form. The twins are simulated and compared with the
FMUs by <code>tests/test_twins.py</code>.</p>
</html>"));
end QuadCoSim;
