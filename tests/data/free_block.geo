<?xml version="1.0" standalone="no"?>
<Berkeley:DDA xmlns:Berkeley="http://www.tsoft.com/~bdoolin/dda">
<!-- one free 2 x 1 block pushed at its centroid: written for srdda's tests -->
<Berkeley:Geometry>
   <Berkeley:Edgenodedist distance="0.01"/>
   <Jointlist>
      <Joint type="1"> 0 0 2 0 </Joint>
      <Joint type="1"> 2 0 2 1 </Joint>
      <Joint type="1"> 2 1 0 1 </Joint>
      <Joint type="1"> 0 1 0 0 </Joint>
   </Jointlist>
   <Loadpointlist> <Point> 1 0.5 </Point> </Loadpointlist>
   <Measuredpointlist> <Point> 1 0.5 </Point> </Measuredpointlist>
</Berkeley:Geometry>
</Berkeley:DDA>
