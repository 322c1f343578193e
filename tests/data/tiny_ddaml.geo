<?xml version="1.0" standalone="no"?>
<!DOCTYPE DDA SYSTEM "geometry.dtd">
<Berkeley:DDA xmlns:Berkeley="http://www.tsoft.com/~bdoolin/dda">
<!-- a two-block sample written for srdda's tests -->
<Berkeley:Geometry>
   <Berkeley:Edgenodedist distance="0.01"/>
   <Jointlist>
      <Joint type="1"> 0 0 4 0 </Joint>
      <Joint type="1"> 4 0 4 1 </Joint>
      <Joint type="1"> 4 1 0 1 </Joint>
      <Joint type="1"> 0 1 0 0 </Joint>
      <Joint type="2"> 1 1 1 2 </Joint>
      <Joint type="2"> 1 2 2 2 </Joint>
      <Joint type="2"> 2 2 2 1 </Joint>
   </Jointlist>
   <Fixedpointlist>
      <Line> -0.5 0.5 4.5 0.5 </Line>
   </Fixedpointlist>
   <Loadpointlist> <Point> 1.5 1.5 </Point> </Loadpointlist>
   <Measuredpointlist> <Point> 1.5 1.2 </Point> </Measuredpointlist>
   <Boltlist> <Bolt> 0 0 1 1 </Bolt> </Boltlist>
</Berkeley:Geometry>
</Berkeley:DDA>
