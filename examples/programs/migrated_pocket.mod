MODULE MigratedPocket
    !***********************************************************
    !
    ! Module:  MigratedPocket
    !
    ! Description:
    !   Mills the outline of a pocket. Taught on another cell (the
    !   part on the robot's other side) and moved to this IRB 6700
    !   by editing the work object: the positions are right in the
    !   new work object, the confdata are still the old cell's.
    !   ConfJ\Off and ConfL\Off let the controller take the arm
    !   configuration nearest the one it has, as migrated programs
    !   are run. Example for deflex offline --program-in.
    !
    ! Author: deflex examples
    !
    ! Version: 1.0
    !
    !***********************************************************
    PERS tooldata tMill:=[TRUE,[[0,0,250],[1,0,0,0]],[6,[0,0,100],[1,0,0,0],0,0,0]];
    TASK PERS wobjdata wobjFixture:=[FALSE,TRUE,"",[[1300,-200,500],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
    CONST jointtarget jHome:=[[-5,20,15,0,55,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pApproach:=[[100,100,80],[0,0,1,0],[-2,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pCorner1:=[[100,100,0],[0,0,1,0],[-2,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pCorner2:=[[300,100,0],[0,0,1,0],[-2,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pCorner3:=[[300,300,0],[0,0,1,0],[-1,1,-2,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pCorner4:=[[100,300,0],[0,0,1,0],[-1,1,-2,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST speeddata vMill:=[50,500,5000,1000];

    !***********************************************************
    !
    ! Procedure main
    !
    !   Home, approach, the pocket's outline, retract, home.
    !
    !***********************************************************
    PROC main()
        MoveAbsJ jHome\NoEOffs,v1000,fine,tMill\WObj:=wobjFixture;
        ConfJ\Off;
        ConfL\Off;
        MoveJ pApproach,v1000,z10,tMill\WObj:=wobjFixture;
        MoveL pCorner1,vMill,fine,tMill\WObj:=wobjFixture;
        MoveL pCorner2,vMill,z1,tMill\WObj:=wobjFixture;
        MoveL pCorner3,vMill,z1,tMill\WObj:=wobjFixture;
        MoveL pCorner4,vMill,z1,tMill\WObj:=wobjFixture;
        MoveL pCorner1,vMill,fine,tMill\WObj:=wobjFixture;
        MoveL pApproach,v200,z10,tMill\WObj:=wobjFixture;
        ConfJ\On;
        ConfL\On;
        MoveAbsJ jHome\NoEOffs,v1000,fine,tMill\WObj:=wobjFixture;
    ENDPROC
ENDMODULE
