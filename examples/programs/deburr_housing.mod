MODULE DeburrHousing
    !***********************************************************
    !
    ! Module:  DeburrHousing
    !
    ! Description:
    !   Deburrs the top edge of a pump housing with a spindle.
    !   RobotStudio-style example for deflex offline --program-in
    !   (ABB IRB 6700-300/2.70, the built-in robot).
    !
    ! Author: deflex examples
    !
    ! Version: 1.0
    !
    !***********************************************************
    PERS tooldata tDeburr:=[TRUE,[[40,0,220],[0.965926,0,0.258819,0]],[4.5,[0,0,120],[1,0,0,0],0,0,0]];
    TASK PERS wobjdata wobjHousing:=[FALSE,TRUE,"",[[1400,-300,600],[0.996195,0,0,0.0871557]],[[0,0,0],[1,0,0,0]]];
    CONST jointtarget jHome:=[[0,10,10,0,60,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget Target_10:=[[0,0,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget Target_20:=[[250,0,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget Target_30:=[[325,75,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget Target_40:=[[250,150,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget Edge{3}:=[
        [[150,150,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[50,150,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[0,100,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    CONST num nApproach:=50;
    VAR robtarget pRetract;
    CONST speeddata vDeburr:=[20,500,5000,1000];
    CONST zonedata zDeburr:=[FALSE,0.3,0.3,0.3,0.03,0.3,0.03];

    !***********************************************************
    !
    ! Procedure main
    !
    !   Approach, deburr the edge (line, arc, lines), retract.
    !
    !***********************************************************
    PROC main()
        ConfJ\On;
        ConfL\On;
        MoveAbsJ jHome\NoEOffs,v1000,z50,tDeburr\WObj:=wobjHousing;
        SetDO doSpindleOn,1;
        WaitTime 2;
        MoveJ Offs(Target_10,0,0,nApproach),v1000,z10,tDeburr\WObj:=wobjHousing;
        MoveL Target_10,v50,fine,tDeburr\WObj:=wobjHousing;
        MoveL Target_20,vDeburr,zDeburr,tDeburr\WObj:=wobjHousing;
        MoveC Target_30,Target_40,vDeburr,zDeburr,tDeburr\WObj:=wobjHousing;
        MoveL Edge{1},vDeburr,zDeburr,tDeburr\WObj:=wobjHousing;
        MoveL Edge{2},vDeburr,zDeburr,tDeburr\WObj:=wobjHousing;
        ! A chamfer at the corner: the spindle turned by 15 degrees, 5 mm off the edge.
        MoveL RelTool(Edge{3},0,0,-5\Rz:=15),vDeburr,zDeburr,tDeburr\WObj:=wobjHousing;
        MoveL [[0,40,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],vDeburr,fine,tDeburr\WObj:=wobjHousing;
        ! Retract straight up from wherever the spindle stopped.
        pRetract:=CRobT(\Tool:=tDeburr\WObj:=wobjHousing);
        MoveL Offs(pRetract,0,0,nApproach),v200,z10,tDeburr\WObj:=wobjHousing;
        SetDO doSpindleOn,0;
        MoveJ Offs(Target_10,0,0,nApproach),v1000,z10,tDeburr\WObj:=wobjHousing;
        MoveAbsJ jHome\NoEOffs,v1000,fine,tDeburr\WObj:=wobjHousing;
    ENDPROC
ENDMODULE
